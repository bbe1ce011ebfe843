"""Recording runs to MCAP and reading them back: the writer, the reader, replay analyses, .btlog export.

Not named ``logging``: that would shadow the standard library. Names are imported lazily, so a run that
only writes does not pay for importing the reader (and the reverse).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # what __getattr__ gives, for the type checker
    from bt_grasp.recording.reader import NodeInfo as NodeInfo
    from bt_grasp.recording.reader import NodeUpdate as NodeUpdate
    from bt_grasp.recording.reader import RunLog as RunLog
    from bt_grasp.recording.reader import TickRecord as TickRecord
    from bt_grasp.recording.reader import TreeSnapshot as TreeSnapshot
    from bt_grasp.recording.reader import open_log as open_log
    from bt_grasp.recording.schemas import BoxMarker as BoxMarker
    from bt_grasp.recording.schemas import PoseMarker as PoseMarker
    from bt_grasp.recording.writer import RunRecorder as RunRecorder

_WHERE = {
    "NodeInfo": "reader",
    "NodeUpdate": "reader",
    "RunLog": "reader",
    "TickRecord": "reader",
    "TreeSnapshot": "reader",
    "open_log": "reader",
    "BoxMarker": "schemas",
    "PoseMarker": "schemas",
    "RunRecorder": "writer",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> object:
    if name in _WHERE:
        return getattr(importlib.import_module(f"bt_grasp.recording.{_WHERE[name]}"), name)
    raise AttributeError(f"module 'bt_grasp.recording' has no attribute {name!r}")
