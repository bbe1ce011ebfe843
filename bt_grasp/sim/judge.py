"""The judge: did the run achieve its :data:`bt_grasp.goals.Goal`, by physics? Reads the oracle (judge only).

One checker per goal kind (a table, not a chain of ifs); each returns the conditions it checked, so a
verdict says which one failed. The pipeline never calls this: only the episode's summary, tests and
benchmarks do.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from bt_grasp.goals import ClearGoal, Goal, PickGoal
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import World

#: an object counts as lifted once its centre rose this much
LIFTED_M = 0.02
#: slack on a pick's lift height (the grip settles a little)
LIFT_SLACK_M = 0.01


class Criterion(enum.StrEnum):
    """A condition a goal kind checks (new goal kinds add theirs)."""

    TARGET_EXISTS = "target_exists"  # the scene has an object the goal can be about
    HELD = "held"  # the object is between both fingers, touching them
    LIFTED = "lifted"  # the object rose by at least the goal's height
    AREA_CLEAR = "area_clear"  # no object inside the scene's work area


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

    def __init__(self, world: World) -> None:
        self._world = world
        self._oracle = GroundTruthOracle(world)
        self._start_z = {n: self._oracle.T_world_object(n)[2, 3] for n in self._oracle.object_names()}

    def check(self, goal: Goal) -> Verdict:
        """The verdict on ``goal`` now. Raises ValueError for a goal :func:`can_judge` refuses."""
        problem = cannot_judge(goal)
        if problem is not None:
            raise ValueError(problem)
        return _CHECKS[goal.kind](self, goal)

    def rises(self) -> dict[str, float]:
        return {n: float(self._oracle.T_world_object(n)[2, 3] - z) for n, z in self._start_z.items()}

    def objects_in_workspace(self) -> tuple[str, ...]:
        """Objects still inside the scene's work area."""
        ws = self._world.config.workspace
        inside = []
        for name in self._oracle.object_names():
            x, y = self._oracle.T_world_object(name)[:2, 3]
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


#: goal kind -> its checker (a new kind adds one line here)
_CHECKS: dict[str, Callable[[Judge, Goal], Verdict]] = {
    "pick": _check_pick,
    "clear": _check_clear,
}


def cannot_judge(goal: Goal) -> str | None:
    """Why the judge cannot check ``goal`` (a kind or variant with no checker yet), or None."""
    if goal.kind not in _CHECKS:
        return f"the judge has no checker for goal kind '{goal.kind}' yet; judged kinds: {', '.join(_CHECKS)}"
    if isinstance(goal, ClearGoal) and goal.into is not None:
        return "the judge does not check 'clear into a container' yet (only 'clear' of the work area)"
    return None
