"""Colour names scene files may use (objects, fixtures, the table), as linear-ish sRGB in [0, 1]."""

from __future__ import annotations

RGB = tuple[float, float, float]

COLOR_NAMES: dict[str, RGB] = {
    "red": (0.85, 0.08, 0.08),
    "green": (0.10, 0.70, 0.15),
    "blue": (0.08, 0.20, 0.85),
    "yellow": (0.90, 0.80, 0.05),
    "orange": (0.95, 0.45, 0.05),
    "purple": (0.50, 0.10, 0.70),
    "white": (0.92, 0.92, 0.92),
    "grey": (0.5, 0.5, 0.5),
    "black": (0.05, 0.05, 0.05),
    "wood": (0.62, 0.48, 0.33),
}


def check_color(value: str | RGB) -> str | RGB:
    """A validator: a known name or an [r, g, b] triple in 0..1 (ValueError with one sentence otherwise)."""
    if isinstance(value, str) and value not in COLOR_NAMES:
        raise ValueError(f"unknown colour '{value}'; known: {', '.join(COLOR_NAMES)} or [r, g, b] in 0..1")
    if not isinstance(value, str) and not all(0.0 <= c <= 1.0 for c in value):
        raise ValueError("an [r, g, b] colour has components in 0..1")
    return value


def rgb_of(value: str | RGB) -> RGB:
    return COLOR_NAMES[value] if isinstance(value, str) else value
