"""Fault plans and injectors that wrap the same interfaces a real fault would hit (see docs/faults.md).

``load_fault_plan`` reads a plan file and ``--inject`` strings; ``install_faults`` wraps a prepared run's
camera, robot, planner, kinematics and calibration and arms faults on leaf entries or ticks.
"""

from bt_grasp.faults.model import FaultKind
from bt_grasp.faults.plan import Fault, FaultPlan, Trigger, load_fault_plan

__all__ = ["Fault", "FaultKind", "FaultPlan", "Trigger", "load_fault_plan"]
