"""A RealSense camera's settings: what is streamed, how long a frame may take, what the library does to depth."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.errors import InputError


class DepthFilter(enum.StrEnum):
    """librealsense's post-processing filters bt_grasp applies to depth before aligning it to colour.

    Applied in the order Intel's post-processing guide gives, whatever order they are named in: spatial and
    temporal smoothing in the disparity domain (``disparity_transform``), then hole filling in depth.
    """

    SPATIAL = "spatial"  # edge-preserving smoothing within a frame (rs.spatial_filter, its defaults)
    TEMPORAL = "temporal"  # smoothing over the last frames, per pixel (rs.temporal_filter, its defaults)
    HOLE_FILLING = "hole-filling"  # invalid pixels take a neighbour's depth (rs.hole_filling_filter, its defaults)


#: the order the filters run in (Intel's "Depth Post-Processing for RealSense D400" white paper)
FILTER_ORDER = (DepthFilter.SPATIAL, DepthFilter.TEMPORAL, DepthFilter.HOLE_FILLING)


@dataclass(frozen=True)
class RealSenseSettings:
    """How a RealSense source is read.

    ``width_px``/``height_px``/``fps``: the colour and depth streams asked of a live device (a recording keeps
    its own); ``timeout_ms``: a frame set that does not arrive within this many milliseconds of wall time is a
    dropped frame (``capture`` returns None); ``settle_frames``: frame sets skipped after a live device starts,
    while its auto exposure settles (a recording is read from its first frame); ``filters``: the depth
    post-processing filters; ``preset``: a RealSense Viewer preset (JSON) loaded into a live device before
    streaming.
    """

    width_px: int = 640
    height_px: int = 480
    fps: int = 30
    timeout_ms: int = 1000
    settle_frames: int = 30
    filters: tuple[DepthFilter, ...] = ()
    preset: Path | None = None

    def __post_init__(self) -> None:
        if self.width_px <= 0 or self.height_px <= 0 or self.fps <= 0:
            raise InputError("camera settings", f"a stream is a positive size and rate, not "
                             f"{self.width_px}x{self.height_px} at {self.fps} fps")
        if self.timeout_ms <= 0:
            raise InputError("camera settings", f"the frame timeout must be positive, got {self.timeout_ms} ms")
        if self.settle_frames < 0:
            raise InputError("camera settings", f"settling frames cannot be negative, got {self.settle_frames}")

    @property
    def ordered_filters(self) -> tuple[DepthFilter, ...]:
        """The filters asked for, each once, in the order they run."""
        return tuple(f for f in FILTER_ORDER if f in self.filters)


def parse_filters(text: str) -> tuple[DepthFilter, ...]:
    """``spatial,temporal,hole-filling`` (any subset, any order; empty: none); InputError naming the bad one."""
    names = [part.strip() for part in text.split(",") if part.strip()]
    known = ", ".join(f.value for f in DepthFilter)
    out = []
    for name in names:
        try:
            out.append(DepthFilter(name))
        except ValueError:
            raise InputError("--filters", f"'{name}' is not a depth filter; known: {known}") from None
    return tuple(out)
