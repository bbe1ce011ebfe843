"""Recording runs to MCAP and reading them back: the writer, the reader, replay analyses, .btlog export.

Not named ``logging``: that would shadow the standard library.
"""

from bt_grasp.recording.reader import NodeInfo, NodeUpdate, RunLog, TickRecord, TreeSnapshot, open_log
from bt_grasp.recording.schemas import BoxMarker, PoseMarker
from bt_grasp.recording.writer import RunRecorder

__all__ = [
    "BoxMarker",
    "NodeInfo",
    "NodeUpdate",
    "PoseMarker",
    "RunLog",
    "RunRecorder",
    "TickRecord",
    "TreeSnapshot",
    "open_log",
]
