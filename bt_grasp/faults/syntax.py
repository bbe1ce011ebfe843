"""The compact ``--inject`` syntax: ``KIND@TRIGGER[:KEY=VALUE,...]``.

TRIGGER is ``tick:N`` (arm after tick N), ``LEAF#N`` (on entering LEAF for the Nth time; ``LEAF`` alone
is ``LEAF#1``), ``LEAF~P`` (probability P on every entry of LEAF) or ``~P`` (on every leaf entry).
KEY=VALUE pairs set the kind's parameters; ``count`` and ``name`` set the entry's own fields. Values are
read as YAML scalars (``3``, ``0.05``, ``true``, ``red_box``). Examples::

    frame_drop@Perceive#1
    planner_fail@tick:50:calls=2
    slip@Lift#1:friction=0.02
    nudge@PlanGrasp#1:dy_m=0.05,count=1
"""

from __future__ import annotations

import re

from bt_grasp.errors import InputError
from bt_grasp.files.bounded_yaml import scalar_or_text

#: short names accepted on the command line
KIND_ALIASES = {
    "drop": "frame_drop",
    "burst": "depth_burst",
    "hole": "depth_hole",
    "calib": "calibration_offset",
    "stall": "controller_stall",
    "slip": "gripper_slip",
    "nudge": "object_nudge",
    "timeout": "leaf_timeout",
}
ENTRY_KEYS = ("count", "name")

_KIND = re.compile(r"^[A-Za-z_]+$")
_LEAF = r"[A-Za-z_][A-Za-z0-9_./-]*"
_NTH = re.compile(rf"^(?P<leaf>{_LEAF})(?:#(?P<nth>\d+))?$")
_PROB = re.compile(rf"^(?P<leaf>{_LEAF}|\*)?~(?P<p>[0-9]*\.?[0-9]+(?:[eE]-?\d+)?)$")
_TICK = re.compile(r"^tick:(?P<tick>\d+)$")


def _bad(text: str, problem: str) -> InputError:
    expected = "expected KIND@TRIGGER[:KEY=VALUE,...], e.g. frame_drop@Perceive#1"
    return InputError("--inject", f"'{text}': {problem}; {expected}")


def _split_trigger(text: str, rest: str) -> tuple[str, str]:
    """(trigger, params text) from what follows the '@'."""
    if rest.startswith("tick:"):
        head, _, tail = rest[len("tick:") :].partition(":")
        return f"tick:{head}", tail
    trigger, _, tail = rest.partition(":")
    return trigger, tail


def _trigger(text: str, trigger: str) -> dict[str, object]:
    if m := _TICK.match(trigger):
        return {"at_tick": int(m["tick"])}
    if m := _PROB.match(trigger):
        leaf = m["leaf"]
        out: dict[str, object] = {"probability": float(m["p"])}
        if leaf not in (None, "*"):
            out["on_leaf"] = leaf
        return out
    if m := _NTH.match(trigger):
        return {"on_leaf": m["leaf"], "nth": int(m["nth"] or 1)}
    raise _bad(text, f"cannot read the trigger '{trigger}' (tick:N, LEAF#N, LEAF~P or ~P)")


def _pairs(text: str, tail: str) -> dict[str, object]:
    out: dict[str, object] = {}
    for item in filter(None, (p.strip() for p in tail.split(","))):
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise _bad(text, f"'{item}' is not KEY=VALUE")
        if key in out:
            raise _bad(text, f"'{key}' is given twice")
        out[key] = scalar_or_text(value, keep_null=True)
    return out


def parse_inject(text: str) -> dict[str, object]:
    """One ``--inject`` string as the mapping a plan file's entry would hold (not yet validated)."""
    kind, sep, rest = text.strip().partition("@")
    if not sep or not kind or not rest:
        raise _bad(text, "missing '@' between the kind and the trigger")
    if not _KIND.match(kind):
        raise _bad(text, f"'{kind}' is not a fault kind")
    trigger, tail = _split_trigger(text, rest)
    entry: dict[str, object] = {"kind": KIND_ALIASES.get(kind, kind), **_trigger(text, trigger)}
    params = _pairs(text, tail)
    for key in ENTRY_KEYS:
        if key in params:
            entry[key] = params.pop(key)
    if params:
        entry["params"] = params
    return entry
