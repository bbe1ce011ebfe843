"""How far below its grip a held object can hang: what Lift adds so that the object itself rises its height.

A grasp off the object's centre of mass holds it by a lever (a bowl by its rim, a pan by its handle, a rod near
one end). The pads' pressure and friction resist the lever's torque only so far: the object may turn about the
grip as it leaves the table (the household bowl, held by its rim 63 mm from its centre, turns 15-27 degrees in
the pads), and its centre then rises less than the tool. The judge of a pick asks that the object's centre rise
the goal's height; Lift, given the perceived object, raises the tool by that height plus the most the object can
sink by turning about the grip:

    turning about the grip point g, the centre c stays |c - g| from g, so at worst it ends straight below g:
    it can sink at most (c_z - g_z) + |c - g| relative to the grip (0 when c is already straight below g).

Only perceived and planned data: ``g`` is the planned grasp's tcp (the pads' centre), ``c`` the detection's
centroid (the centre of its fitted box). No model of friction or of how far the object will really turn: an
upper bound, so an object that stays level rises up to that much more than asked (never less). The bound is
capped at :data:`MAX_HANG_M`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: the most a lift adds for the object's hang, m (a lever longer than this is far outside the gripper's objects)
MAX_HANG_M = 0.10


def hang_allowance_m(grip_base_m: Sequence[float], centre_base_m: Sequence[float]) -> float:
    """How far the object's centre can sink relative to the grip by turning about it (base frame, m), in
    [0, MAX_HANG_M]; 0 when either point is not finite."""
    grip = np.asarray(grip_base_m, dtype=float).reshape(3)
    centre = np.asarray(centre_base_m, dtype=float).reshape(3)
    if not (np.all(np.isfinite(grip)) and np.all(np.isfinite(centre))):
        return 0.0
    lever = centre - grip
    sink = float(np.linalg.norm(lever)) + float(lever[2])
    return min(MAX_HANG_M, max(0.0, sink))


def lift_rise_m(height_m: float, grip_base_m: Sequence[float] | None,
                centre_base_m: Sequence[float] | None) -> float:
    """How far the tool rises so that the object rises ``height_m``: the height plus the hang allowance when
    both the grip and the object's centre are known, else the height alone."""
    if grip_base_m is None or centre_base_m is None:
        return float(height_m)
    return float(height_m) + hang_allowance_m(grip_base_m, centre_base_m)


__all__ = ["MAX_HANG_M", "hang_allowance_m", "lift_rise_m"]
