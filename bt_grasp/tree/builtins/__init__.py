"""Every built-in node type, with BT.CPP v4's registration IDs and port names."""

from __future__ import annotations

from bt_grasp.tree.builtins import actions, controls, decorators
from bt_grasp.tree.registry import NodeKind, NodeRegistry, NodeSpec, PortDirection, PortSpec

IN, INOUT = PortDirection.INPUT, PortDirection.INOUT
STATUS_NAMES = ("SUCCESS", "FAILURE", "SKIPPED", "RUNNING")


def _control(cls: type, description: str, ports: tuple[PortSpec, ...] = (), children=(1, None)) -> NodeSpec:  # type: ignore[no-untyped-def]
    return NodeSpec(cls.__name__, NodeKind.CONTROL, ports, cls, description, children=children)


def _decorator(cls: type, description: str, ports: tuple[PortSpec, ...] = ()) -> NodeSpec:
    return NodeSpec(cls.__name__, NodeKind.DECORATOR, ports, cls, description)


def builtin_specs() -> tuple[NodeSpec, ...]:
    """The specs :func:`register_builtins` adds (SubTree is handled by the loader, not registered)."""
    c, d, a = controls, decorators, actions
    code = PortSpec("code", IN, str, description="the script to run")
    return (
        _control(c.Sequence, "Ticks children in order; resumes a RUNNING child; restarts after a FAILURE."),
        _control(c.SequenceWithMemory, "Like Sequence, but resumes at the failed child next time."),
        _control(c.ReactiveSequence, "Re-evaluates every child each tick; a FAILURE halts the RUNNING one."),
        _control(c.Fallback, "Ticks children in order until one succeeds."),
        _control(c.ReactiveFallback, "Re-evaluates every child each tick; a SUCCESS halts the RUNNING one."),
        _control(
            c.Parallel,
            "Ticks all children; succeeds/fails when enough of them did.",
            (
                PortSpec("success_count", IN, int, -1, "children that must succeed (-1: all)"),
                PortSpec("failure_count", IN, int, 1, "children that must fail (-1: all)"),
            ),
        ),
        _control(c.IfThenElse, "If child 1 succeeds tick child 2, else child 3 (or FAILURE).", children=(2, 3)),
        _control(c.WhileDoElse, "Re-checks child 1 every tick; runs child 2 or child 3.", children=(2, 3)),
        _decorator(d.Inverter, "Swaps SUCCESS and FAILURE."),
        _decorator(d.ForceSuccess, "SUCCESS whenever the child completes."),
        _decorator(d.ForceFailure, "FAILURE whenever the child completes."),
        _decorator(
            d.RetryUntilSuccessful,
            "Ticks the child again after a FAILURE, up to num_attempts times.",
            (PortSpec("num_attempts", IN, int, description="attempts before failing (-1: forever)"),),
        ),
        _decorator(
            d.Repeat,
            "Ticks the child again after a SUCCESS, num_cycles times.",
            (PortSpec("num_cycles", IN, int, description="repetitions (-1: forever)"),),
        ),
        _decorator(
            d.Timeout,
            "Halts the child and fails after msec of simulated time.",
            (PortSpec("msec", IN, int, description="time limit in milliseconds"),),
        ),
        _decorator(
            d.Delay,
            "Waits delay_msec of simulated time before ticking the child.",
            (PortSpec("delay_msec", IN, int, description="delay in milliseconds"),),
        ),
        _decorator(d.KeepRunningUntilFailure, "RUNNING after each child SUCCESS; FAILURE when it fails."),
        _decorator(
            d.RunOnce,
            "Ticks the child until it completes once.",
            (PortSpec("then_skip", IN, bool, True, "afterwards SKIPPED (true) or the same status (false)"),),
        ),
        _decorator(
            d.Precondition,
            "Ticks the child only when the script `if` is true.",
            (
                PortSpec("if", IN, str, description="the condition script"),
                PortSpec("else", IN, str, "FAILURE", "status when the condition is false", STATUS_NAMES),
            ),
        ),
        NodeSpec("AlwaysSuccess", NodeKind.ACTION, (), a.AlwaysSuccess, "Returns SUCCESS."),
        NodeSpec("AlwaysFailure", NodeKind.ACTION, (), a.AlwaysFailure, "Returns FAILURE."),
        NodeSpec(
            "SetBlackboard",
            NodeKind.ACTION,
            (
                PortSpec("value", IN, object, description="the value, or {entry} to copy"),
                PortSpec("output_key", INOUT, str, description="the entry to write"),
            ),
            a.SetBlackboard,
            "Writes a value into a blackboard entry.",
        ),
        NodeSpec(
            "Sleep",
            NodeKind.ACTION,
            (PortSpec("msec", IN, int, description="duration in milliseconds of simulated time"),),
            a.Sleep,
            "RUNNING until msec of simulated time passed.",
        ),
        NodeSpec("Script", NodeKind.ACTION, (code,), a.Script, "Runs a script; SUCCESS."),
        NodeSpec("ScriptCondition", NodeKind.CONDITION, (code,), a.ScriptCondition, "SUCCESS if the script is true."),
        NodeSpec(
            "FailureIs",
            NodeKind.CONDITION,
            (
                PortSpec("reason", IN, str, description="a failure reason such as NO_DETECTION"),
                PortSpec("leaf", IN, str, "", "only when this leaf (by name) failed"),
            ),
            a.FailureIs,
            "SUCCESS when the last leaf failure had this reason.",
        ),
    )


def register_builtins(registry: NodeRegistry) -> None:
    for spec in builtin_specs():
        registry.register(spec)


#: BT.CPP 3.x names that 4.x removed, with the replacement to suggest
REMOVED_V3_NAMES: dict[str, str] = {
    "SequenceStar": "SequenceWithMemory",
    "FallbackStar": "Fallback",
    "ReactiveFallbackStar": "ReactiveFallback",
    "BlackboardCheckInt": "Precondition or ScriptCondition",
    "BlackboardCheckDouble": "Precondition or ScriptCondition",
    "BlackboardCheckString": "Precondition or ScriptCondition",
    "RetryUntilSuccesful": "RetryUntilSuccessful",
}
