"""ur_rtde's Python modules, imported on first use; without them, one sentence and exit code 2."""

from __future__ import annotations

from types import ModuleType

from bt_grasp.errors import BtGraspError

#: how to get ur_rtde (the sentence every refusal ends with)
INSTALL_HINT = "install the extra with `pip install -e '.[hardware]'` (ur-rtde 1.6.5 and pyrealsense2)"


class UrRtdeUnavailable(BtGraspError):
    """ur_rtde cannot be imported: a UR arm was asked for without the ``hardware`` (or ``ur``) extra."""

    exit_code = 2

    def __init__(self, what: str) -> None:
        super().__init__(f"{what} needs ur_rtde, which is not installed: {INSTALL_HINT}")


def ur_rtde(what: str = "a UR arm") -> tuple[ModuleType, ModuleType]:
    """``(rtde_control, rtde_receive)``; :class:`UrRtdeUnavailable` naming ``what`` when they are missing."""
    try:
        import rtde_control
        import rtde_receive
    except ImportError:
        raise UrRtdeUnavailable(what) from None
    return rtde_control, rtde_receive
