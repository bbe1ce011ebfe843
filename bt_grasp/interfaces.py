"""The small interfaces through which perception, motion and behaviours reach the (simulated) hardware.

``bt_grasp.sim`` implements them with SAPIEN; tests implement them with stand-ins; ``bt_grasp.faults``
wraps them to inject faults. None of them exposes simulator ground truth (true object or camera poses):
that lives only in ``bt_grasp.sim.oracle``.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:  # annotations only: numpy is imported where arrays are made (not for --help)
    import numpy as np
    from numpy.typing import NDArray


class Mount(enum.StrEnum):
    """Where the camera is: fixed in the cell looking at the robot, or on the robot's wrist."""

    EYE_TO_HAND = "eye-to-hand"
    EYE_IN_HAND = "eye-in-hand"


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics in OpenCV's convention (pixel centres at integer coordinates)."""

    width_px: int
    height_px: int
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float

    @property
    def K(self) -> NDArray[np.float64]:
        import numpy as np

        return np.array([[self.fx_px, 0.0, self.cx_px], [0.0, self.fy_px, self.cy_px], [0.0, 0.0, 1.0]])

    def to_dict(self) -> dict[str, float | int]:
        return {
            "width_px": self.width_px,
            "height_px": self.height_px,
            "fx_px": self.fx_px,
            "fy_px": self.fy_px,
            "cx_px": self.cx_px,
            "cy_px": self.cy_px,
        }


@dataclass(frozen=True)
class RGBDFrame:
    """One aligned colour + depth capture.

    ``color`` is (H, W, 3) uint8 RGB; ``depth_m`` is (H, W) float32 metres along the optical axis, 0 where
    invalid (out of range, depth shadow). Both are in the colour camera's optical frame (OpenCV axes:
    x right, y down, z forward).
    """

    color: NDArray[np.uint8]
    depth_m: NDArray[np.float32]
    intrinsics: CameraIntrinsics
    stamp_ns: int
    mount: Mount
    frame_id: str = "camera_color_optical_frame"


class Camera(Protocol):
    """An RGB-D camera. ``capture`` returns None when no frame arrived (a dropped frame)."""

    @property
    def intrinsics(self) -> CameraIntrinsics: ...

    @property
    def mount(self) -> Mount: ...

    def capture(self) -> RGBDFrame | None: ...


class Robot(Protocol):
    """A position-controlled 6-DoF arm with a parallel-jaw gripper."""

    @property
    def joint_names(self) -> tuple[str, ...]: ...

    def joint_positions(self) -> NDArray[np.float64]:
        """Measured arm joint positions, rad (6,)."""
        ...

    def joint_velocities(self) -> NDArray[np.float64]:
        """Measured arm joint velocities, rad/s (6,)."""
        ...

    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        """Command the joint drives (position and optional velocity feed-forward)."""
        ...

    def open_gripper(self) -> None: ...

    def close_gripper(self, force_n: float | None = None) -> None:
        """Close the fingers with a bounded force (N per finger); None uses the configured default."""
        ...

    def gripper_width_m(self) -> float:
        """Measured opening between the finger pads, metres."""
        ...

    def gripper_target_width_m(self) -> float:
        """The commanded opening, metres."""
        ...


class Encoder(Protocol):
    """A conveyor belt's incremental encoder, as a cell reads it: whole counts of the belt's travel since the run
    started (they grow as the belt runs its direction), ``counts_per_m`` of them per metre; one count is its
    quantisation. The simulator counts the belt's own drive motion (``bt_grasp.sim.conveyor.BeltEncoder``)."""

    @property
    def counts_per_m(self) -> float: ...

    def counts(self) -> int: ...


class Stepper(Protocol):
    """Advances the world by whole physics steps; the only way time passes in a run."""

    @property
    def dt_s(self) -> float: ...

    def step(self, n: int = 1) -> None: ...

    def now_ns(self) -> int: ...
