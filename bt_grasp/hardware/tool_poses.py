"""The tool poses an eye-in-hand recording carries beside it: ``FILE.poses.jsonl`` next to ``FILE.db3``.

A wrist camera moves with the arm: a frame is placed in the robot's base frame by the tool pose at its capture
(``T_base_camera = T_base_tool @ T_tool_camera``, the calibration giving the second). pyrealsense2's recordings hold
camera data only, so the poses go in a JSON-lines file beside the recording, one object a frame, stamped like the
frames (the device timestamp of the frame's depth picture, ns)::

    {"stamp_ns": 1234000000, "parent_frame": "base_link", "child_frame": "tool0",
     "matrix": [[r00, r01, r02, x], [r10, r11, r12, y], [r20, r21, r22, z], [0, 0, 0, 1]]}

The matrix is written with Python's shortest round-trip float text, so a pose read back is the pose written, bit
for bit. The file is read whole (at most :data:`MAX_POSES_BYTES`), every line checked; a bad line is one sentence
naming the file and line.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import read_user_file

#: a poses file is at most this large (a line is ~250 bytes: about 250,000 frames, over two hours at 30 fps)
MAX_POSES_BYTES = 64 << 20
SUFFIX = ".poses.jsonl"


@dataclass(frozen=True)
class ToolPose:
    """The tool's pose in the base frame when the frame stamped ``stamp_ns`` was captured."""

    stamp_ns: int
    T_base_tool: NDArray[np.float64]
    parent_frame: str = "base_link"
    child_frame: str = "tool0"

    def to_line(self) -> str:
        rows = [[float(v) for v in row] for row in np.asarray(self.T_base_tool, dtype=float)]
        return json.dumps({"stamp_ns": int(self.stamp_ns), "parent_frame": self.parent_frame,
                           "child_frame": self.child_frame, "matrix": rows}, separators=(", ", ": "))


def poses_path(recording: str | Path) -> Path:
    """Where a recording's tool poses live: ``rec.db3`` -> ``rec.poses.jsonl``."""
    path = Path(recording)
    return path.with_name(path.stem + SUFFIX)


def write_poses(path: str | Path, poses: Iterable[ToolPose]) -> Path:
    """Write the poses file whole (``bt_grasp.files.output_files``: never half-written)."""
    # deferred: written only when a recording is complete
    from bt_grasp.files.output_files import write_output_file

    text = "".join(pose.to_line() + "\n" for pose in poses)
    return write_output_file(path, text, "--out", example="recording.poses.jsonl")


def _matrix(value: object) -> NDArray[np.float64] | None:
    if not (isinstance(value, list) and len(value) == 4 and all(isinstance(r, list) and len(r) == 4 for r in value)):
        return None
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for r in value for v in r):
        return None
    T = np.array(value, dtype=float)
    R = T[:3, :3]
    if not np.allclose(T[3], [0, 0, 0, 1]) or not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        return None
    return T


def read_poses(path: str | Path) -> dict[int, ToolPose]:
    """The poses by stamp; :class:`InputError` (file, line, problem) for anything but the format above."""
    path = Path(path)
    text = read_user_file(path, MAX_POSES_BYTES)
    try:
        lines = text.decode("utf-8").splitlines()
    except UnicodeDecodeError:
        raise InputError(path, "is not UTF-8 text (a poses file is JSON lines)") from None
    poses: dict[int, ToolPose] = {}
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            item = json.loads(line)
        except json.JSONDecodeError as exc:
            raise InputError(path, f"is not JSON lines ({exc.msg})", where=number) from None
        if not isinstance(item, dict) or set(item) != {"stamp_ns", "parent_frame", "child_frame", "matrix"}:
            raise InputError(path, "a line is an object with stamp_ns, parent_frame, child_frame and matrix",
                             where=number)
        stamp, parent, child = item["stamp_ns"], item["parent_frame"], item["child_frame"]
        if not isinstance(stamp, int) or isinstance(stamp, bool) or stamp < 0:
            raise InputError(path, f"stamp_ns must be a non-negative integer, got {stamp!r}", where=number)
        if not (isinstance(parent, str) and isinstance(child, str) and parent and child):
            raise InputError(path, "parent_frame and child_frame must be frame names", where=number)
        T = _matrix(item["matrix"])
        if T is None:
            raise InputError(path, "matrix must be a finite 4x4 rigid transform (rows, last row 0 0 0 1)",
                             where=number)
        if stamp in poses:
            raise InputError(path, f"stamp_ns {stamp} appears twice", where=number)
        poses[stamp] = ToolPose(stamp, T, parent, child)
    if not poses:
        raise InputError(path, "holds no pose")
    return poses
