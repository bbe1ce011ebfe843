"""Typed choices of the command line (issue 24): every option whose set of values is fixed is an enum here, so
``--help`` lists the values, the shell completes them and the parser refuses any other value in the one error
format (``bt-grasp: error: Invalid value for '--goal': 'lift' is not one of 'pick', 'clear'.``).

The values are kept literal, not derived from the modules that define them, because ``--help`` and completion
import no simulator, planner or task code (``tests/test_cli_choices.py`` checks each set against its source:
``COMMAND_LINE_KINDS``, ``PLANNERS``, ``TASKS``, ``Mount``). Camera mounts use :class:`bt_grasp.interfaces.Mount`
itself (a light module).
"""

from __future__ import annotations

from enum import StrEnum

from bt_grasp.interfaces import Mount


class GoalChoice(StrEnum):
    """`run --goal`: the goals a command line can ask for (``bt_grasp.scene.run_goal.COMMAND_LINE_KINDS``; the
    others need a scene's names: declare them in the scene file)."""

    pick = "pick"
    clear = "clear"


class PlannerChoice(StrEnum):
    """`bench plan --planner`: the OMPL planners bt_grasp wires (``bt_grasp.motion.planner.PLANNERS``)."""

    RRTConnect = "RRTConnect"
    RRT = "RRT"
    RRTstar = "RRTstar"
    InformedRRTstar = "InformedRRTstar"
    SORRTstar = "SORRTstar"
    BITstar = "BITstar"
    AORRTC = "AORRTC"


class TaskChoice(StrEnum):
    """`bench tasks --task`: the shipped tasks (``bt_grasp.bench.tasks.TASKS``), in the suite's order."""

    pick = "pick"
    pick_and_place = "pick_and_place"
    stack = "stack"
    sort_by_color = "sort_by_color"
    clear_table = "clear_table"
    clear_household = "clear_household"


class ChoiceList:
    """A comma-separated list of an enum's values (``--mounts eye-to-hand,eye-in-hand``) as typer's ``parser``
    and ``autocompletion``: each item checked (ValueError names the bad one), each completed by the shell (after
    the last comma), the choices shown as the metavar in ``--help``. The value stays the normalised text (items
    stripped, empty ones dropped), so the command splits it as before."""

    def __init__(self, choices: type[StrEnum]) -> None:
        self.choices = tuple(member.value for member in choices)
        self.metavar = f"[{'|'.join(self.choices)}][,...]"

    def __call__(self, value: str) -> str:
        items = [item.strip() for item in str(value).split(",") if item.strip()]
        known = ", ".join(repr(c) for c in self.choices)
        if not items:
            raise ValueError(f"expected one or more of {known}, separated by commas")
        for item in items:
            if item not in self.choices:
                raise ValueError(f"{item!r} is not one of {known}.")
        return ",".join(items)

    def complete(self, incomplete: str) -> list[str]:
        head, _, last = incomplete.rpartition(",")
        done = set(head.split(",")) if head else set()
        return [f"{head},{c}" if head else c for c in self.choices if c.startswith(last) and c not in done]


#: ``bench follow --mounts``: camera mounts, comma-separated
MOUNT_LIST = ChoiceList(Mount)

__all__ = ["MOUNT_LIST", "ChoiceList", "GoalChoice", "Mount", "PlannerChoice", "TaskChoice"]
