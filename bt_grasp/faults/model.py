"""The typed shape of a fault plan: one strict model per fault kind's parameters, one for a fault entry.

A plan file is a mapping ``faults:`` -> a list of entries; every entry names a ``kind``, a trigger
(``at_tick`` | ``on_leaf`` + ``nth`` | ``probability`` [+ ``on_leaf``]), a ``count`` and ``params``.
Units are in the field names (``_m``, ``_mm``, ``_deg``, ``_s``, ``_px``, ``_n``).
"""

from __future__ import annotations

import enum
import math
from typing import Literal

from pydantic import Field, model_validator

from bt_grasp.files.config import StrictModel


class FaultKind(enum.StrEnum):
    FRAME_DROP = "frame_drop"
    DEPTH_BURST = "depth_burst"
    DEPTH_HOLE = "depth_hole"
    CALIBRATION_OFFSET = "calibration_offset"
    IK_FAIL = "ik_fail"
    PLANNER_FAIL = "planner_fail"
    CONTROLLER_STALL = "controller_stall"
    GRIPPER_SLIP = "gripper_slip"
    OBJECT_NUDGE = "object_nudge"
    LEAF_TIMEOUT = "leaf_timeout"


# --- parameters of each kind ----------------------------------------------------------------------------


class FrameDropParams(StrictModel):
    frames: int = Field(1, ge=1, description="consecutive captures that return no frame")


class DepthBurstParams(StrictModel):
    frames: int = Field(1, ge=1, description="consecutive captures hit by the burst")
    sigma_m: float = Field(0.03, gt=0.0, le=1.0, description="standard deviation of the added depth noise, m")
    fraction: float = Field(1.0, gt=0.0, le=1.0, description="share of valid pixels that get the noise")


class DepthHoleParams(StrictModel):
    frames: int = Field(1, ge=1, description="consecutive captures with the hole")
    u_px: int = Field(160, ge=0, description="left column of the missing rectangle, px")
    v_px: int = Field(120, ge=0, description="top row of the missing rectangle, px")
    width_px: int = Field(320, ge=1, description="width of the missing rectangle, px")
    height_px: int = Field(240, ge=1, description="height of the missing rectangle, px")


class CalibrationOffsetParams(StrictModel):
    dx_mm: float = Field(0.0, description="translation added along the reference frame's x, mm")
    dy_mm: float = 0.0
    dz_mm: float = 0.0
    droll_deg: float = Field(0.0, description="rotation about x added at the camera origin, degrees")
    dpitch_deg: float = 0.0
    dyaw_deg: float = 0.0

    @model_validator(mode="after")
    def _not_zero(self) -> CalibrationOffsetParams:
        values = (self.dx_mm, self.dy_mm, self.dz_mm, self.droll_deg, self.dpitch_deg, self.dyaw_deg)
        if not all(math.isfinite(v) for v in values):
            raise ValueError("offsets must be finite numbers")
        if all(v == 0.0 for v in values):
            raise ValueError("a calibration offset needs at least one non-zero component")
        return self


class ServiceFailParams(StrictModel):
    calls: int = Field(1, ge=1, description="how many calls of the service fail")
    within_attempt: bool = Field(False, description="drop unused failing calls when the armed leaf's attempt ends")


class PlannerFailParams(ServiceFailParams):
    status: Literal["no_path", "timeout"] = Field("no_path", description="the failure status the planner returns")


class ControllerStallParams(StrictModel):
    duration_s: float = Field(3.0, gt=0.0, le=60.0, description="simulated time the drives hold the last target")


class GripperSlipParams(StrictModel):
    friction: float | None = Field(0.02, ge=0.0, le=2.0, description="finger pad friction while the slip lasts")
    #: PhysX averages the pad's and the object's friction, so a low pad friction alone rarely lets a 40 N grip
    #: slip (measured: a 0.1 kg box held at pad friction 0.05); the force limit is what makes it slip
    force_n: float | None = Field(2.0, ge=0.0, description="finger drive force limit until the next gripper command")
    duration_s: float = Field(2.0, gt=0.0, le=60.0, description="simulated time before the pad friction recovers")

    @model_validator(mode="after")
    def _something(self) -> GripperSlipParams:
        if self.friction is None and self.force_n is None:
            raise ValueError("a gripper slip needs 'friction' or 'force_n'")
        return self


class ObjectNudgeParams(StrictModel):
    object: str | None = Field(None, description="scene object to push; default: the one of the tree's colour")
    dx_m: float = Field(0.0, description="intended slide along the world x axis, m")
    dy_m: float = Field(0.04, description="intended slide along the world y axis, m")

    @model_validator(mode="after")
    def _distance(self) -> ObjectNudgeParams:
        distance = math.hypot(self.dx_m, self.dy_m)
        if not 0.0 < distance <= 0.2:
            raise ValueError(f"a nudge slides 0 < d <= 0.2 m; dx_m, dy_m give {distance:.3f} m")
        return self


class LeafTimeoutParams(StrictModel):
    duration_s: float = Field(5.0, gt=0.0, le=120.0, description="simulated time the cell stops responding")


PARAMS: dict[FaultKind, type[StrictModel]] = {
    FaultKind.FRAME_DROP: FrameDropParams,
    FaultKind.DEPTH_BURST: DepthBurstParams,
    FaultKind.DEPTH_HOLE: DepthHoleParams,
    FaultKind.CALIBRATION_OFFSET: CalibrationOffsetParams,
    FaultKind.IK_FAIL: ServiceFailParams,
    FaultKind.PLANNER_FAIL: PlannerFailParams,
    FaultKind.CONTROLLER_STALL: ControllerStallParams,
    FaultKind.GRIPPER_SLIP: GripperSlipParams,
    FaultKind.OBJECT_NUDGE: ObjectNudgeParams,
    FaultKind.LEAF_TIMEOUT: LeafTimeoutParams,
}


# --- one entry of a plan ----------------------------------------------------------------------------------


class FaultEntry(StrictModel):
    """A fault as written: kind, trigger, count, raw params (validated per kind by the loader)."""

    kind: FaultKind
    name: str | None = Field(None, description="a label for logs and the /faults topic")
    at_tick: int | None = Field(None, ge=1, description="arm after this tick (and later ticks while count lasts)")
    on_leaf: str | None = Field(None, min_length=1, description="a leaf's name, type or path")
    nth: int | None = Field(None, ge=1, description="arm on entering on_leaf for the nth time (and later entries)")
    probability: float | None = Field(None, gt=0.0, le=1.0, description="chance to arm on each leaf entry")
    count: int = Field(1, ge=1, le=1000, description="how many times the fault may fire")
    params: dict[str, object] | None = None  # checked against the kind's model by the loader

    @model_validator(mode="after")
    def _one_trigger(self) -> FaultEntry:
        if self.at_tick is not None and (self.on_leaf, self.nth, self.probability) != (None, None, None):
            raise ValueError("at_tick cannot be combined with on_leaf, nth or probability")
        if self.nth is not None and self.probability is not None:
            raise ValueError("choose one trigger: nth or probability, not both")
        if self.nth is not None and self.on_leaf is None:
            raise ValueError("nth needs on_leaf (the leaf whose entries are counted)")
        if self.at_tick is None and self.on_leaf is None and self.probability is None:
            raise ValueError("a fault needs a trigger: at_tick, on_leaf (+ nth) or probability")
        return self


class FaultPlanFile(StrictModel):
    faults: list[FaultEntry] = Field(min_length=1)
