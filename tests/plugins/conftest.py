"""Installed plugins without installing anything: ``installed`` is the list of entry points the plugin loader
discovers (``importlib.metadata.entry_points`` replaced for the test), each a :class:`FakeEntryPoint`."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import pytest

from bt_grasp.tree import plugins


@dataclass
class FakeEntryPoint:
    name: str
    value: str
    target: Any
    dist_name: str

    @property
    def dist(self) -> SimpleNamespace:
        return SimpleNamespace(name=self.dist_name)

    def load(self) -> Any:
        if isinstance(self.target, BaseException):
            raise self.target
        return self.target


@pytest.fixture
def installed(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[FakeEntryPoint]]:
    found: list[FakeEntryPoint] = []
    groups: list[str] = []

    def entry_points(group: str) -> list[FakeEntryPoint]:
        groups.append(group)
        return list(found)

    monkeypatch.setattr(plugins, "entry_points", entry_points)
    plugins.entry_point_plugins.cache_clear()
    yield found
    plugins.entry_point_plugins.cache_clear()
    assert set(groups) <= {"bt_grasp.leaves"} and len(groups) <= 1  # discovered once per process
