"""BehaviorTree.CPP's script language (BT.CPP ``src/scripting``): the parser and the evaluated expressions
with BT.CPP's value model."""

from __future__ import annotations

from bt_grasp.tree.scripting.operators import Env, Program
from bt_grasp.tree.scripting.parser import parse_script

__all__ = ["Env", "Program", "parse_script"]
