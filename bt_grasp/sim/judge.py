"""The judge: did the run achieve its :data:`bt_grasp.scene.goals.Goal`, by physics? Reads the oracle (judge only).

One checker per goal kind (a table, not a chain of ifs); each returns the conditions it checked, so a
verdict says which one failed. Where an object is comes from its true geometry (:func:`object_extent`): its
centre is the centre of its own-frame bounds, its bottom and top the lowest and highest point of its shape as
it lies now, so a mesh whose origin is its bottom, or a bottle lying on its side, is judged like a box.
The pipeline never calls this: only the episode's summary, tests and benchmarks do.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bt_grasp.geometry import Mat4, signed_mm
from bt_grasp.interfaces import Mount
from bt_grasp.scene.fixtures import Container
from bt_grasp.scene.goals import ClearGoal, CollectGoal, Goal, PickGoal, PlaceGoal, SortGoal, StackGoal
from bt_grasp.sim.judge_view import Extent, object_extent
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.placement import Placement, PlacementTracker
from bt_grasp.sim.world import World

#: an object counts as lifted once its centre (the centre of its own-frame bounds) rose this much
LIFTED_M = 0.02
#: slack on a pick's lift height (the grip settles a little)
LIFT_SLACK_M = 0.01


class Criterion(enum.StrEnum):
    """A condition a goal kind checks (new goal kinds add theirs)."""

    TARGET_EXISTS = "target_exists"  # the scene has an object the goal can be about
    HELD = "held"  # the object is between both fingers, touching them
    LIFTED = "lifted"  # the object rose by at least the goal's height
    AREA_CLEAR = "area_clear"  # no object inside the scene's work area
    RELEASED = "released"  # placed objects: picked up, let go, no finger touching them
    UPRIGHT = "upright"  # placed objects: tilted at most 10 degrees
    RESTING = "resting"  # placed objects: still for 1 s of simulated time after release
    SET_DOWN = "set_down"  # placed objects: fell less than 1 cm after the fingers opened (not dropped)
    AT_TARGET = "at_target"  # place: centre within the tolerance of the target, on its surface
    ON_TOP = "on_top"  # stack: centred on the lower object, bottom resting on its top
    IN_CONTAINER = "in_container"  # sort / clear into: inside the container, on its floor


@dataclass(frozen=True)
class Condition:
    criterion: Criterion
    met: bool
    detail: str  # what the judge measured, as a short phrase


@dataclass(frozen=True)
class Verdict:
    """What the simulator's ground truth says about the end of a run, for one goal."""

    goal: Goal
    conditions: tuple[Condition, ...]
    object_name: str | None = None  # the object the goal is about (pick), if any
    object_lift_m: float = 0.0  # its rise since the start of the run
    in_gripper: bool = False
    lifted_objects: tuple[str, ...] = ()  # every object that rose by LIFTED_M or more
    objects_in_workspace: tuple[str, ...] = ()

    @property
    def success(self) -> bool:
        return bool(self.conditions) and all(c.met for c in self.conditions)

    @property
    def failed(self) -> Condition | None:
        """The first condition not met (None on success)."""
        return next((c for c in self.conditions if not c.met), None)


class Judge:
    """Built at the start of a run (it remembers where every object started); ``check`` at its end."""

    def __init__(self, world: World, oracle: GroundTruthOracle | None = None) -> None:
        self._world = world
        self._oracle = GroundTruthOracle(world) if oracle is None else oracle
        self._start_z = {n: self.extent(n).center_m[2] for n in self._oracle.object_names()}
        self.tracker = PlacementTracker(self._oracle)
        self.observe()

    def now_s(self) -> float:
        return self._world.now_ns() * 1e-9

    def observe(self) -> None:
        """Once per tick (and while settling): releases and motion, for placement goals."""
        self.tracker.observe(self.now_s())

    @staticmethod
    def places(goal: Goal) -> bool:
        """Whether ``goal`` is judged by where objects came to rest after release (what :meth:`observe` tracks);
        a pick or a clear-the-table goal is judged by the state at the end alone."""
        return not (isinstance(goal, PickGoal) or (isinstance(goal, ClearGoal) and goal.into is None))

    def settle_ticks(self, goal: Goal) -> int:
        """Ticks the world must still run after the tree ended so a placement goal's 'resting for 1 s after
        release' can be seen (0 for goals that place nothing)."""
        if not self.places(goal):
            return 0
        tick_s = self._world.steps_per_tick * self._world.dt_s
        return math.ceil(self.tracker.settle_s(self.now_s()) / tick_s) + 1

    def placement(self, name: str) -> Placement:
        return self.tracker.placement(name, self.now_s())

    def check(self, goal: Goal) -> Verdict:
        """The verdict on ``goal`` now. Raises ValueError for a goal :func:`can_judge` refuses."""
        problem = cannot_judge(goal)
        if problem is not None:
            raise ValueError(problem)
        return _CHECKS[goal.kind](self, goal)

    def extent(self, name: str) -> Extent:
        """Where object ``name``'s true geometry is now (centre, bottom, top; world frame)."""
        spec = self._world.config.object_spec(name)
        if spec is None:
            raise ValueError(f"no object '{name}' in the scene file")
        return object_extent(spec, self._oracle.T_world_object(name))

    def rises(self) -> dict[str, float]:
        """How far each object's centre rose since the start of the run (since it entered, for an object a
        conveyor's feed set down during the run)."""
        for name, T in self._world.entered.items():
            if name not in self._start_z:
                spec = self._world.config.object_spec(name)
                assert spec is not None
                self._start_z[name] = object_extent(spec, T).center_m[2]
        return {n: self.extent(n).center_m[2] - z for n, z in self._start_z.items()}

    def object_poses(self) -> dict[str, list[list[float]]]:
        """Every object's ``T_world_object`` now (4x4 lists): the end of a run's fingerprint."""
        return {n: self._oracle.T_world_object(n).tolist() for n in self._oracle.object_names()}

    def objects_in_workspace(self) -> tuple[str, ...]:
        """Objects still inside the scene's work area."""
        ws = self._world.config.workspace
        inside = []
        for name in self._oracle.object_names():
            x, y = self.extent(name).center_xy_m
            if ws.x_m[0] <= x <= ws.x_m[1] and ws.y_m[0] <= y <= ws.y_m[1]:
                inside.append(name)
        return tuple(inside)

    def objects_of_color(self, color: str) -> tuple[str, ...]:
        """The scene's objects of a colour name ('' = every object)."""
        return tuple(o.name for o in self._world.config.objects if not color or o.color == color)

    def in_gripper(self, name: str) -> bool:
        return self._oracle.object_in_gripper(name)


def _check_pick(judge: Judge, goal: Goal) -> Verdict:
    assert isinstance(goal, PickGoal)
    rises = judge.rises()
    lifted = tuple(n for n, r in rises.items() if r > LIFTED_M)
    if goal.object is not None:
        candidates = [goal.object] if goal.object in rises else []
    else:
        candidates = [n for n in judge.objects_of_color(goal.color or "") if n in rises]
    if not candidates:
        what = f"no object '{goal.object}'" if goal.object else (
            f"no object of colour '{goal.color}'" if goal.color else "no object")
        return Verdict(goal, (Condition(Criterion.TARGET_EXISTS, False, f"{what} in the scene"),),
                       lifted_objects=lifted)
    name = max(candidates, key=lambda n: rises[n])  # of that colour, the one that rose most
    rise, held = rises[name], judge.in_gripper(name)
    conditions = (
        Condition(Criterion.TARGET_EXISTS, True, name),
        Condition(Criterion.HELD, held, f"{name} {'between' if held else 'not between'} the fingers"),
        Condition(Criterion.LIFTED, rise >= goal.height_m - LIFT_SLACK_M,
                  f"{name} rose {rise * 100:.1f} cm of {goal.height_m * 100:.1f} cm"),
    )
    return Verdict(goal, conditions, name, rise, held, lifted)


def _check_clear(judge: Judge, goal: Goal) -> Verdict:
    assert isinstance(goal, ClearGoal) and goal.into is None
    left = judge.objects_in_workspace()
    detail = f"left in the work area: {', '.join(left)}" if left else "nothing left in the work area"
    rises = judge.rises()
    return Verdict(goal, (Condition(Criterion.AREA_CLEAR, not left, detail),),
                   lifted_objects=tuple(n for n, r in rises.items() if r > LIFTED_M), objects_in_workspace=left)


def _placed_conditions(judge: Judge, placements: list[Placement], upright: bool = True,
                       set_down: bool = True) -> list[Condition]:
    """One condition per placement criterion over every object (naming the ones that miss it): released,
    upright (when the goal asks), resting, set down (when the goal asks)."""
    out = []
    wanted = (Criterion.RELEASED, *((Criterion.UPRIGHT,) if upright else ()), Criterion.RESTING,
              *((Criterion.SET_DOWN,) if set_down else ()))
    for criterion in wanted:
        misses = [detail for p in placements for c, detail in p.problems() if c == criterion.value]
        measured = "; ".join(p.measured()[criterion.value] for p in placements)
        out.append(Condition(criterion, not misses, "; ".join(misses) if misses else measured))
    return out


def _missing(goal: Goal, names: list[str], judge: Judge) -> Verdict | None:
    known = set(judge._oracle.object_names())
    absent = [n for n in names if n not in known]
    if not absent and names:
        return None
    detail = f"no object {', '.join(absent)} in the scene" if absent else "no object the goal is about"
    return Verdict(goal, (Condition(Criterion.TARGET_EXISTS, False, detail),))


def _check_place(judge: Judge, goal: Goal) -> Verdict:
    assert isinstance(goal, PlaceGoal)
    missing = _missing(goal, [goal.object], judge)
    if missing is not None:
        return missing
    scene = judge._world.config
    fixture = scene.fixture(goal.at) if goal.at is not None else None
    xy = goal.at_xy_m if goal.at_xy_m is not None else (fixture.center_xy_m if fixture else (0.0, 0.0))
    surface = float(fixture.surface_z_m) if fixture is not None else 0.0
    p, extent = judge.placement(goal.object), judge.extent(goal.object)
    off = float(np.hypot(extent.center_m[0] - xy[0], extent.center_m[1] - xy[1]))
    bottom = extent.bottom_z_m - surface
    at = off <= goal.tolerance_m and abs(bottom) <= 0.005
    detail = (f"{goal.object} {off * 100:.1f} cm from the target (tolerance {goal.tolerance_m * 100:.1f} cm), "
              f"its bottom {signed_mm(bottom, 'above', 'below')} the target surface")
    conditions = [Condition(Criterion.TARGET_EXISTS, True, goal.object),
                  *_placed_conditions(judge, [p], upright=goal.upright), Condition(Criterion.AT_TARGET, at, detail)]
    return Verdict(goal, tuple(conditions), goal.object)


def _check_stack(judge: Judge, goal: Goal) -> Verdict:
    assert isinstance(goal, StackGoal)
    missing = _missing(goal, [goal.object, goal.on], judge)
    if missing is not None:
        return missing
    top, lower = judge.placement(goal.object), judge.placement(goal.on)
    upper_at, lower_at = judge.extent(goal.object), judge.extent(goal.on)
    off = float(np.hypot(upper_at.center_m[0] - lower_at.center_m[0], upper_at.center_m[1] - lower_at.center_m[1]))
    dz = upper_at.bottom_z_m - lower_at.top_z_m
    ok = off <= goal.xy_tolerance_m and abs(dz) <= goal.z_tolerance_m and lower.upright
    detail = (f"{goal.object} {off * 100:.1f} cm off {goal.on}'s centre (at most {goal.xy_tolerance_m * 100:.0f}), "
              f"its bottom {signed_mm(dz, 'above', 'below')} {goal.on}'s top (at most "
              f"{goal.z_tolerance_m * 1000:.0f} mm)"
              + ("" if lower.upright else f", {goal.on} tilts {lower.tilt_deg:.0f} deg"))
    conditions = [Condition(Criterion.TARGET_EXISTS, True, f"{goal.object} on {goal.on}"),
                  *_placed_conditions(judge, [top], upright=goal.upright), Condition(Criterion.ON_TOP, ok, detail)]
    return Verdict(goal, tuple(conditions), goal.object)


def _in_container(judge: Judge, goal: Goal, wanted: dict[str, str], upright: bool, set_down: bool) -> Verdict:
    """Each object of ``wanted`` (name -> container) inside its container, on its floor, released and at rest
    (and upright, and set down, when asked)."""
    scene = judge._world.config
    if not wanted:
        return Verdict(goal, (Condition(Criterion.TARGET_EXISTS, False, "no object the goal is about"),))
    placements = [judge.placement(n) for n in wanted]
    outside = []
    for p in placements:
        box = scene.fixture(wanted[p.name])
        extent = judge.extent(p.name)
        inside = (isinstance(box, Container) and box.contains_xy(extent.center_xy_m)
                  and extent.bottom_z_m <= box.surface_z_m + 0.01)
        if not inside:
            outside.append(f"{p.name} not on the floor of {wanted[p.name]}")
    conditions = [Condition(Criterion.TARGET_EXISTS, True, ", ".join(wanted)),
                  *_placed_conditions(judge, placements, upright, set_down),
                  Condition(Criterion.IN_CONTAINER, not outside, "; ".join(outside) or "every object inside")]
    return Verdict(goal, tuple(conditions), objects_in_workspace=judge.objects_in_workspace())


def _check_sort(judge: Judge, goal: Goal) -> Verdict:
    assert isinstance(goal, SortGoal)
    wanted = {n: rule.into for rule in goal.rules for n in judge.objects_of_color(rule.color)}
    return _in_container(judge, goal, wanted, upright=goal.upright, set_down=True)


def _check_clear_into(judge: Judge, goal: Goal) -> Verdict:
    """Every object inside the container, released and at rest (what a user clearing a table into a bin means:
    any way up, dropped in or set down), unless the goal asks ``upright``/``set_down`` too."""
    assert isinstance(goal, ClearGoal) and goal.into is not None
    return _in_container(judge, goal, {n: goal.into for n in judge._oracle.object_names()},
                         upright=goal.upright, set_down=goal.set_down)


def _check_collect(judge: Judge, goal: Goal) -> Verdict:
    """At least ``count`` objects placed inside the container (released, upright, resting, set down, on its floor)."""
    assert isinstance(goal, CollectGoal)
    box = judge._world.config.fixture(goal.into)
    placed = []
    for name in judge._oracle.object_names():
        extent = judge.extent(name)
        inside = (isinstance(box, Container) and box.contains_xy(extent.center_xy_m)
                  and extent.bottom_z_m <= box.surface_z_m + 0.01)
        if inside and not judge.placement(name).problems():
            placed.append(name)
    detail = f"{len(placed)} of {goal.count} placed in {goal.into}" + (f": {', '.join(placed)}" if placed else "")
    return Verdict(goal, (Condition(Criterion.IN_CONTAINER, len(placed) >= goal.count, detail),),
                   objects_in_workspace=judge.objects_in_workspace())


#: goal kind -> its checker (a new kind adds one line here)
_CHECKS: dict[str, Callable[[Judge, Goal], Verdict]] = {
    "pick": _check_pick,
    "clear": lambda judge, goal: _check_clear_into(judge, goal) if getattr(goal, "into", None) else _check_clear(
        judge, goal),
    "place": _check_place,
    "stack": _check_stack,
    "sort": _check_sort,
    "collect": _check_collect,
}


def cannot_judge(goal: Goal) -> str | None:
    """Why the judge cannot check ``goal`` (a kind with no checker yet), or None."""
    if goal.kind not in _CHECKS:
        return f"the judge has no checker for goal kind '{goal.kind}' yet; judged kinds: {', '.join(_CHECKS)}"
    return None


def true_camera_pose(world: World, mount: str, tool_link: str) -> Mat4:
    """What a hand-eye calibration should find (judge only): the true ``T_base_camera`` (eye-to-hand) or
    ``T_tool_camera`` (eye-in-hand), in OpenCV's optical axes."""
    oracle = GroundTruthOracle(world)
    if mount == Mount.EYE_TO_HAND:
        return oracle.T_base_camera_cv()
    return np.linalg.inv(oracle.T_world_link(tool_link)) @ oracle.T_world_camera_cv()
