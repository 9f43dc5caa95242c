"""ONNX Runtime execution providers chosen by the perception config: the pure choice, and the
real YOLOX session on this CPU-only machine (cuda falls back and says why; strict refuses)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from dronewrapper.runtime.config import load_config
from dronewrapper_perception.config import Config
from dronewrapper_perception.detectors import build_detector
from dronewrapper_perception.providers import (
    CPU,
    CUDA,
    TENSORRT,
    ProviderError,
    choose_providers,
    dropped_at_start,
    provider_name,
    refusal,
)
from dronewrapper_perception.yolox import YoloxDetector
from support import YOLOX_NANO

CPU_ONLY = ["AzureExecutionProvider", CPU]
GPU_BUILD = [TENSORRT, CUDA, CPU]


def test_names_and_aliases():
    assert provider_name("cuda") == CUDA
    assert provider_name(" TensorRT ") == TENSORRT
    assert provider_name("cpu") == CPU
    assert provider_name("Auto") == "auto"
    assert provider_name("OpenVINOExecutionProvider") == "OpenVINOExecutionProvider"
    with pytest.raises(ProviderError, match="unknown execution provider 'cdua'"):
        provider_name("cdua")


def test_cpu_by_default_and_cpu_always_last():
    for requested in (None, [], ["cpu"]):
        choice = choose_providers(requested, CPU_ONLY)
        assert choice.providers == (CPU,) and not choice.missing and not choice.wanted
    choice = choose_providers(["cpu", "cuda"], GPU_BUILD)
    assert choice.providers == (CUDA, CPU)


def test_cuda_missing_from_the_build_falls_back_and_says_why():
    choice = choose_providers(["cuda"], CPU_ONLY)
    assert choice.providers == (CPU,)
    assert choice.missing == (CUDA,)
    reason = choice.fallback_reason(CPU_ONLY)
    assert "CUDAExecutionProvider is not available" in reason
    assert "onnxruntime-gpu" in reason
    assert "CUDAExecutionProvider" in refusal(choice, [CPU], CPU_ONLY)
    assert "not in this onnxruntime build" in refusal(choice, [CPU], CPU_ONLY)


def test_auto_takes_the_best_there_is():
    assert choose_providers(["auto"], GPU_BUILD).providers == (TENSORRT, CUDA, CPU)
    only_cuda = choose_providers(["auto"], [CUDA, CPU])
    assert only_cuda.providers == (CUDA, CPU)
    assert only_cuda.missing == ()  # auto expects some to be absent
    assert refusal(only_cuda, [CUDA, CPU], [CUDA, CPU]) == ""
    cpu_only = choose_providers(["auto"], CPU_ONLY)
    assert cpu_only.providers == (CPU,)
    assert "no GPU provider could be used" in refusal(cpu_only, [CPU], CPU_ONLY)


def test_a_provider_the_session_could_not_start_is_named():
    choice = choose_providers(["tensorrt", "cuda"], GPU_BUILD)
    assert choice.providers == (TENSORRT, CUDA, CPU)
    # e.g. the TensorRT libraries are missing: onnxruntime drops it while creating the session
    active = [CUDA, CPU]
    assert dropped_at_start(choice, active) == [TENSORRT]
    assert "could not start" in refusal(choice, active, GPU_BUILD)
    assert refusal(choice, GPU_BUILD, GPU_BUILD) == ""


def test_config_validates_provider_names():
    config = load_config(Config, overrides=["providers=auto", "providers_strict=true"])
    assert config.provider_list() == ["auto"] and config.providers_strict
    with pytest.raises(Exception, match="providers: unknown execution provider 'gpu'"):
        load_config(Config, overrides=["providers=cuda,gpu"])


def test_yolox_asked_for_cuda_on_this_cpu_machine_runs_on_cpu_and_logs_why(caplog):
    with caplog.at_level(logging.WARNING, logger="dronewrapper_perception.yolox"):
        detector = YoloxDetector(YOLOX_NANO, providers=["cuda"], threads=1)
    assert detector.providers == [CPU]
    assert any("CUDAExecutionProvider is not available" in r.message for r in caplog.records)
    assert detector.detect(np.zeros((48, 64, 3), np.uint8)) == []


def test_strict_providers_refuse_the_cpu_fallback():
    with pytest.raises(ProviderError, match="refusing to fall back"):
        YoloxDetector(YOLOX_NANO, providers=["cuda"], strict_providers=True)
    config = load_config(
        Config,
        overrides=[
            "detector=yolox",
            f"model_path={YOLOX_NANO}",
            "providers=auto",
            "providers_strict=true",
        ],
    )
    with pytest.raises(ProviderError, match="no GPU provider could be used"):
        build_detector(config)
    # auto without strict: quietly the CPU (no GPU here is expected, not an error)
    relaxed = load_config(
        Config, overrides=["detector=yolox", f"model_path={YOLOX_NANO}", "providers=auto"]
    )
    assert build_detector(relaxed).providers == [CPU]
