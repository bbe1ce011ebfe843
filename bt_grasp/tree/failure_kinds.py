"""Which failures are control flow, not faults: the one rule every reader of failures applies.

A node's FAILURE is *false by design* when it answers a question rather than reports a fault: a condition asked
by a Fallback (its "no" selects the next child), a condition answering "no" without a reason, or a control node or
decorator failing by itself with no reason (``ForceFailure``, ``Inverter``). The tick loop applies it as a run goes
(``bt_grasp.tree.runner``: the live failure line, the causal chain, ``--break fail``) and ``replay --failures``
applies it to a log (``bt_grasp.recording.replay``): the same function, so a run and its log never disagree.
"""

from __future__ import annotations


def false_by_design(*, is_leaf: bool, kind: str, parent_type: str | None, reason: str | None) -> bool:
    """``kind``: the node's BT.CPP kind (``Condition``, ``Action``, ...); ``parent_type``: its parent's node type
    (``Fallback``, ``ReactiveFallback``, ``Sequence``, ...; None for the root)."""
    if not is_leaf:
        return reason is None
    if kind != "Condition":
        return False
    return reason is None or (parent_type is not None and "Fallback" in parent_type)
