"""A script's progress on stderr at INFO unless the application configured logging."""

from __future__ import annotations

import logging

from dronewrapper.script_log import ProgressHandler, show_progress


def test_a_script_sees_the_sdks_progress_and_a_configured_app_does_not(capsys, monkeypatch):
    logger = logging.getLogger("dronewrapper.progress_test")
    monkeypatch.setattr(logger, "handlers", [])
    monkeypatch.setattr(logger, "level", logging.NOTSET)
    # alone: a ProgressHandler another test left on the "dronewrapper" parent would print twice
    monkeypatch.setattr(logger, "propagate", False)
    show_progress(logger)
    show_progress(logger)  # once
    assert sum(isinstance(h, ProgressHandler) for h in logger.handlers) == 1
    root = logging.getLogger()
    monkeypatch.setattr(root, "handlers", [])  # a script: nothing configured
    logger.info("takeoff: reached %.2f m", 2.5)
    logger.debug("not shown")
    assert capsys.readouterr().err == "[dronewrapper.progress_test] takeoff: reached 2.50 m\n"
    monkeypatch.setattr(root, "handlers", [logging.NullHandler()])  # the app configured logging
    logger.info("takeoff: reached %.2f m", 2.5)
    assert capsys.readouterr().err == ""


def test_a_level_the_application_set_is_kept(monkeypatch):
    logger = logging.getLogger("dronewrapper.progress_level_test")
    monkeypatch.setattr(logger, "handlers", [])
    monkeypatch.setattr(logger, "level", logging.WARNING)
    show_progress(logger)
    assert logger.level == logging.WARNING
