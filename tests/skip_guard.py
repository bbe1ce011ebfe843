"""No silent skips of real-client tests in CI.

The browser tests (Foxglove's web build and the run report in headless Chromium), the Ray cluster tests and the
terminal (tmux) tests skip on a developer's machine that lacks the tool, with the reason in pytest's summary
(`-ra`). Under ``CI=true`` such a skip is a failure: a failed install or a Ray start that never came up must not
turn into a green run. A test is guarded when it lives under ``tests/browser/`` or carries the ``real_client``
marker.
"""

from __future__ import annotations

import os
from collections.abc import Generator
from pathlib import Path

import pytest

GUARDED_FOLDERS = ("browser",)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "real_client: drives a real client tool; a skip fails under CI=true")


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in ("1", "true", "yes")


def is_guarded(item: pytest.Item) -> bool:
    if item.get_closest_marker("real_client") is not None:
        return True
    parts = Path(str(item.path)).parts
    return any(folder in parts[-3:-1] for folder in GUARDED_FOLDERS)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Generator[None, None, None]:
    outcome = yield
    report: pytest.TestReport = outcome.get_result()
    if not (report.skipped and in_ci() and is_guarded(item)):
        return
    if hasattr(report, "wasxfail"):
        return
    reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
    reason = reason.removeprefix("Skipped: ")
    report.outcome = "failed"
    report.longrepr = f"CI=true: a real-client test may not skip ({reason})"
