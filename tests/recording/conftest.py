"""Fixtures of the recording tests; the synthetic runs themselves live in recording_helpers.py."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from recording_helpers import record_run


@pytest.fixture
def make_run(tmp_path: Path) -> Callable[..., tuple[Path, dict[str, Any]]]:
    def make(name: str = "run.mcap", **kwargs: Any) -> tuple[Path, dict[str, Any]]:
        path = tmp_path / name
        return path, record_run(path, **kwargs)

    return make


@pytest.fixture
def ok_run(make_run: Callable[..., tuple[Path, dict[str, Any]]]) -> tuple[Path, dict[str, Any]]:
    return make_run("ok.mcap", grasp_failures=1)


@pytest.fixture
def failed_run(make_run: Callable[..., tuple[Path, dict[str, Any]]]) -> tuple[Path, dict[str, Any]]:
    return make_run("failed.mcap", grasp_failures=5)
