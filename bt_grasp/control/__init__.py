"""Interactive runs that stay reproducible: one typed control interface for every front end.

A front end (the terminal UI, the Foxglove live server, a notebook) holds a :class:`Controller`, sends it
commands and draws its :class:`RunState`; the episode's tick loop consults it between ticks::

    from bt_grasp.control import Controller, Pause, SetBlackboard, Source, Step, parse_breakpoint
    from bt_grasp.episode import EpisodeRequest, run_episode

    control = Controller([parse_breakpoint("fail")])
    # another thread: control.send(SetBlackboard("lift_height", "0.15"), Source.TERMINAL); control.state()
    result = run_episode(request, controller=control)

Interventions (blackboard edits, object choices, faults fired, stop, restart) are applied at tick boundaries
and recorded on ``/control/interventions``; ``replay --resim`` applies them again at their ticks. Watching
(pause, step, breakpoints) is not recorded: a paused run is the same run. See docs/interactive.md.
"""

from bt_grasp.control.breakpoints import BreakKind, Breakpoint, parse_breakpoint, parse_breakpoints
from bt_grasp.control.commands import (
    ChooseObject,
    ClearBreakpoint,
    Command,
    CommandError,
    FireFault,
    Intervention,
    Pause,
    Restart,
    Resume,
    SeedPolicy,
    SetBlackboard,
    SetBreakpoint,
    SetBreakpoints,
    Source,
    Step,
    Stop,
    command_from_json,
    command_to_json,
    is_intervention,
)
from bt_grasp.control.controller import Controller, FaultFirer, InterventionSink, check_breakpoints
from bt_grasp.control.state import DetectionView, FailureView, InterventionRecord, NodeView, RunState

__all__ = [
    "BreakKind", "Breakpoint", "ChooseObject", "ClearBreakpoint", "Command", "CommandError", "Controller",
    "DetectionView", "FailureView", "FaultFirer", "FireFault", "Intervention", "InterventionRecord",
    "InterventionSink", "NodeView", "Pause", "Restart", "Resume", "RunState", "SeedPolicy", "SetBlackboard",
    "SetBreakpoint", "SetBreakpoints", "Source", "Step", "Stop", "check_breakpoints", "command_from_json",
    "command_to_json", "is_intervention", "parse_breakpoint", "parse_breakpoints",
]
