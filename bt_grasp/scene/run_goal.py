"""What a run must achieve, as typed data: the judge (``bt_grasp.sim.judge``) checks it by physics.

The goal types are the scene file's (``bt_grasp.scene.goals``: frozen, strictly validated, one class per
kind, discriminated by ``kind``); this module makes them from a command line or from a scene plus the
run's blackboard. The tree never sees the goal, and the judge never looks at the tree.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from bt_grasp.defaults import DEFAULT_LIFT_HEIGHT_M
from bt_grasp.errors import InputError
from bt_grasp.scene.format import Scene
from bt_grasp.scene.goals import GOAL_KINDS, ClearGoal, Goal, PickGoal
from bt_grasp.scene.objects import SceneObject

__all__ = ["COMMAND_LINE_KINDS", "default_color", "goal_for_run", "goal_from_options"]

#: the kinds a command line can ask for (the others need a scene's names: declare them in the scene)
COMMAND_LINE_KINDS = ("pick", "clear")


def _lift_height(value: float, source: str) -> float:
    if not (math.isfinite(value) and 0.0 < value < 0.6):
        raise InputError(source, f"the lift height must be within (0, 0.6) m, got {value}")
    return float(value)


def goal_from_options(kind: str, color: str = "red", lift_height_m: float = DEFAULT_LIFT_HEIGHT_M,
                      source: str = "--goal") -> Goal:
    """The goal ``--goal KIND --color C --lift-height M`` asks for; InputError naming the flag if bad."""
    if kind not in COMMAND_LINE_KINDS:
        other = [k for k in GOAL_KINDS if k not in COMMAND_LINE_KINDS]
        hint = f" ({', '.join(other)}: declare it in the scene file)" if kind in other else ""
        raise InputError(source, f"expected one of {', '.join(COMMAND_LINE_KINDS)}, got '{kind}'{hint}")
    if kind == "clear":
        return ClearGoal(kind="clear")
    return PickGoal(kind="pick", color=color or None, height_m=_lift_height(lift_height_m, "--lift-height"))


def default_color(objects: Sequence[SceneObject]) -> str:
    """The colour a pick asks for when none is given: 'red' (the first scenes' figures) unless the scene declares
    a mesh or URDF object; then '' (any object: the tree chooses by geometry, whatever the colours drawn)."""
    return "" if any(o.is_mesh for o in objects) else "red"


def goal_for_run(scene: Scene, blackboard: Mapping[str, object]) -> Goal:
    """The scene's declared goal, else today's default: a pick of the run's ``{color}`` lifted by
    ``{lift_height}`` (the entries ``--color``/``--lift-height`` put on the blackboard; no ``color`` entry:
    :func:`default_color`)."""
    if scene.goal is not None:
        return scene.goal
    color = blackboard.get("color", default_color(scene.objects))
    height = blackboard.get("lift_height", DEFAULT_LIFT_HEIGHT_M)
    if not isinstance(color, str):
        raise InputError("--set", f"color must be a colour name, got {color!r}")
    if isinstance(height, bool) or not isinstance(height, int | float):
        raise InputError("--set", f"lift_height must be a number of metres, got {height!r}")
    return PickGoal(kind="pick", color=color or None, height_m=_lift_height(float(height), "--lift-height"))
