"""The run's memory of its attempts follows an object that moved (issue 46): what was tried on it before still
counts after a failed grasp pushed it, after FindLost found it again, and after SetDown set it down elsewhere.
Each fails on the memory before this (attempts matched only where the object was seen when each was made:
centres within 3 cm), where seed 129's L bracket, slid 2.5 cm at each of five slips, counted every attempt as
the first on a new object and was grasped from above five times."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from bt_grasp.behaviours.attempts import AttemptKind, AttemptMemory, GraspFamily, ObjectSeen
from bt_grasp.geometry import make_T, rot_z
from bt_grasp.perception.results import Detection

R_DOWN = np.diag([1.0, -1.0, -1.0])


def bracket(x: float, y: float = 0.0) -> Detection:
    return Detection("object", (0, 0, 1, 1), (x, y, 0.01), (0.09, 0.05, 0.02), 0.0, 100, 1.0)


def top_grasp(det: Detection) -> np.ndarray:
    return make_T(R_DOWN, [det.centroid_base_m[0], det.centroid_base_m[1], 0.02])


def fail_grasp(memory: AttemptMemory, det: Detection, tick: int, reason: str = "SLIPPED") -> None:
    memory.open_grasp("PlanGrasp", tick, det, top_grasp(det), 0.05)
    memory.moving()
    memory.end(reason, "Lift", tick + 50)


def test_an_object_a_failed_grasp_pushed_keeps_its_failures() -> None:
    # five slips, each pushing the bracket 2.5 cm along x: 0.500, 0.525, ... 0.600; every failure counts on it
    memory = AttemptMemory()
    for i in range(5):
        fail_grasp(memory, bracket(0.5 + 0.025 * i), tick=100 * i)
    now = bracket(0.625)
    assert memory.family_failures(now)[GraspFamily.TOP] == 5
    assert memory.object_failures(now) == 5
    assert len(memory.on(now, AttemptKind.GRASP)) == 5


def test_another_object_after_a_failure_is_not_taken_for_the_pushed_one() -> None:
    memory = AttemptMemory()
    fail_grasp(memory, bracket(0.5), tick=0)
    far = bracket(0.5, 0.08)  # like it, 8 cm away: another object
    other = Detection("object", (0, 0, 1, 1), (0.53, 0.0, 0.05), (0.20, 0.03, 0.10), 0.0, 100, 1.0)  # near, unlike
    for det in (far, other):
        fail_grasp(memory, det, tick=200)
    assert memory.family_failures(bracket(0.5))[GraspFamily.TOP] == 1
    assert memory.object_failures(far) == 1 and memory.object_failures(other) == 1


def test_an_object_found_again_or_set_down_elsewhere_keeps_its_attempts() -> None:
    memory = AttemptMemory()
    fail_grasp(memory, bracket(0.5), tick=0)
    rolled = bracket(0.62, -0.20)  # FindLost found it 23 cm away
    memory.moved(memory.attempts[0].object, rolled)
    assert memory.object_failures(rolled) == 1
    # set down by SetDown from there: the grip no placement could take is not taken again where it now lies
    was = ObjectSeen.of(rolled)
    held_grip = make_T(R_DOWN, [0, 0, 0.01])  # the object in the tool frame: 1 cm below the tool, turned over
    memory.place("PlaceIn", 300, rolled, held_grip, GraspFamily.TOP, (0.3, 0.5, 0.0, 0.0), None, [np.eye(4)], True,
                 "PLACE_BLOCKED", moved=False)
    there = dataclasses.replace(was, centroid_m=(0.40, 0.30, 0.01), yaw_deg=90.0)
    memory.moved(was, there)
    now = bracket(0.40, 0.30)
    now = dataclasses.replace(now, yaw_rad=math.pi / 2)
    assert memory.object_failures(now) == 2
    grip = make_T(R_DOWN, [0, 0, 0.01])  # the tool over the object's centre, as the placement held it
    T_same = make_T(rot_z(math.pi / 2), [0.40, 0.30, 0.01]) @ np.linalg.inv(grip)
    why = memory.grasp_exclusion(now, T_same, GraspFamily.TOP, "candidate 0")
    assert why is not None and why.rule == "repeat" and "PLACE_BLOCKED" in why.detail
