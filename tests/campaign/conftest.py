"""Fixtures shared by the campaign tests."""

from __future__ import annotations

from typing import Any

import pytest

from bt_grasp.campaign import plots


@pytest.fixture
def drawn(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """Each figure a plot function draws, caught where it is turned into PNG bytes (the newest last)."""
    caught: list[Any] = []
    real = plots._png

    def keep(fig: Any) -> bytes:
        caught.append(fig)
        return real(fig)

    monkeypatch.setattr(plots, "_png", keep)
    return caught
