"""ONNX Runtime execution providers from the perception config: which to ask for, and what to
say when one cannot be had (pure; the session creation stays in :mod:`yolox`).

Config names: ``cpu``, ``cuda``, ``tensorrt``, ``auto`` (TensorRT, then CUDA, whichever this
onnxruntime build has, else the CPU) or a full provider name (``CUDAExecutionProvider``). The
CPU provider always comes last, so a model whose operators a GPU provider does not take still
runs. A provider can be missing twice over: absent from this onnxruntime build (the ``onnxruntime``
wheel has no CUDA; ``onnxruntime-gpu`` has), or present but unable to start (no GPU, no driver,
CUDA/cuDNN/TensorRT libraries not found), when onnxruntime drops it while creating the session.
Either way perception falls back to the CPU and logs why, unless ``strict`` asks it to refuse.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

CPU = "CPUExecutionProvider"
CUDA = "CUDAExecutionProvider"
TENSORRT = "TensorrtExecutionProvider"

ALIASES = {"cpu": CPU, "cuda": CUDA, "tensorrt": TENSORRT}
AUTO = "auto"
AUTO_ORDER = (TENSORRT, CUDA)
"""What ``auto`` asks for, best first (the CPU is added after them anyway)."""

SUFFIX = "ExecutionProvider"


class ProviderError(ValueError):
    """A provider name that means nothing, or (strict mode) one that cannot be had."""


def provider_name(name: str) -> str:
    """The onnxruntime name of a config name (``cuda`` -> ``CUDAExecutionProvider``).

    Raises:
        ProviderError: neither an alias, ``auto``, nor a name ending in ``ExecutionProvider``.
    """
    key = name.strip()
    if key.lower() in ALIASES:
        return ALIASES[key.lower()]
    if key.lower() == AUTO:
        return AUTO
    if key.endswith(SUFFIX) and len(key) > len(SUFFIX):
        return key
    known = ", ".join([*ALIASES, AUTO])
    raise ProviderError(
        f"unknown execution provider {name!r} (known: {known}, or a full onnxruntime name "
        f"such as {CUDA})"
    )


def check_names(requested: Sequence[str]) -> None:
    """Validate config names (for the config schema). Raises ProviderError naming the bad one."""
    for name in requested:
        provider_name(name)


@dataclass(frozen=True)
class ProviderChoice:
    """The providers to hand onnxruntime, and what was asked for but is not in this build.

    Attributes:
        providers: onnxruntime names in order of preference, the CPU last.
        wanted: the GPU (non-CPU) providers the config asked for, in order.
        missing: those of ``wanted`` this onnxruntime build does not have.
        auto: the config said ``auto`` (missing GPU providers are then expected, not an error).
    """

    providers: tuple[str, ...]
    wanted: tuple[str, ...]
    missing: tuple[str, ...]
    auto: bool = False

    def fallback_reason(self, available: Sequence[str]) -> str:
        """Why the run goes on without the missing providers ("" when nothing is missing)."""
        if not self.missing:
            return ""
        return (
            f"execution provider {', '.join(self.missing)} is not available in this onnxruntime "
            f"build (it has: {', '.join(available) or 'none'}; GPU providers come with the "
            f"onnxruntime-gpu package and NVIDIA's CUDA/cuDNN/TensorRT libraries)"
        )


def choose_providers(requested: Sequence[str] | None, available: Sequence[str]) -> ProviderChoice:
    """The providers to ask onnxruntime for, given the config's ``requested`` names.

    ``None`` or empty: CPU only. Names not in ``available`` are left out (and listed in
    ``missing``); the CPU provider always ends the list.

    Raises:
        ProviderError: an unknown name.
    """
    names = [provider_name(n) for n in (requested or [])]
    auto = AUTO in names
    wanted: list[str] = []
    for name in names:
        for provider in AUTO_ORDER if name == AUTO else (name,):
            if provider != CPU and provider not in wanted:
                wanted.append(provider)
    chosen = [p for p in wanted if p in available]
    missing = [p for p in wanted if p not in available]
    if auto and chosen:
        missing = [p for p in missing if p not in AUTO_ORDER]  # auto took the best one there is
    return ProviderChoice(
        providers=(*chosen, CPU),
        wanted=tuple(wanted),
        missing=tuple(missing),
        auto=auto,
    )


def dropped_at_start(choice: ProviderChoice, active: Sequence[str]) -> list[str]:
    """Providers handed to onnxruntime that its session did not keep (could not start)."""
    return [p for p in choice.providers if p != CPU and p not in active]


def refusal(choice: ProviderChoice, active: Sequence[str], available: Sequence[str]) -> str:
    """Strict mode: why the session must not run ("" when every GPU provider asked for runs).

    With ``auto``, strict means "some GPU provider": it refuses only when none is active.
    """
    gpu_active = [p for p in active if p != CPU]
    if choice.auto:
        if choice.wanted and not gpu_active:
            return (
                f"providers=auto with strict mode: no GPU provider could be used (asked for "
                f"{', '.join(AUTO_ORDER)}; this onnxruntime has {', '.join(available) or 'none'}"
                f"; the session runs on {', '.join(active) or 'nothing'})"
            )
        return ""
    not_running = [p for p in choice.wanted if p not in active]
    if not not_running:
        return ""
    where = (
        "not in this onnxruntime build"
        if set(not_running) & set(choice.missing)
        else (
            "in this onnxruntime build but it could not start (no GPU, driver or CUDA libraries?)"
        )
    )
    return (
        f"strict providers: {', '.join(not_running)} requested but {where}; refusing to fall "
        f"back to the CPU (set providers_strict: false to allow it)"
    )
