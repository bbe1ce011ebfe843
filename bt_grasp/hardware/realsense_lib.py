"""pyrealsense2, imported on first use; without the ``realsense`` extra, one sentence and exit code 2."""

from __future__ import annotations

from types import ModuleType

from bt_grasp.errors import BtGraspError

#: how to get pyrealsense2 (the sentence every refusal ends with)
INSTALL_HINT = "install the extra with `pip install -e '.[realsense]'` (pyrealsense2 2.59, Linux x86_64)"


class RealSenseUnavailable(BtGraspError):
    """pyrealsense2 cannot be imported: a RealSense camera was asked for without the ``realsense`` extra."""

    exit_code = 2

    def __init__(self, what: str) -> None:
        super().__init__(f"{what} needs pyrealsense2, which is not installed: {INSTALL_HINT}")


def pyrealsense2(what: str = "a RealSense camera") -> ModuleType:
    """The ``pyrealsense2`` module; :class:`RealSenseUnavailable` (naming ``what`` needed it) when it is missing."""
    try:
        import pyrealsense2 as rs
    except ImportError:
        raise RealSenseUnavailable(what) from None
    module: ModuleType = rs
    return module
