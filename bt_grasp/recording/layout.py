"""The Foxglove layout shipped with bt_grasp (``bt_grasp/foxglove_layouts/bt_grasp.layout.json``).

3D (the arm, fixtures, point cloud, detections, grasp candidates; the judge's true poses off by default),
the camera image with the detections overlaid, State Transitions of the pick tree's leaves from
``/bt/tick.leaves.<leaf>``, joint-angle and gripper plots, the log and the run result.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path


def layout_path() -> Path:
    return Path(str(files("bt_grasp") / "foxglove_layouts" / "bt_grasp.layout.json"))
