"""py_trees leaves for the pick: thin adapters from the blackboard to perception, motion and the robot.

Every leaf does its long work across ticks (one control period per tick), reports RUNNING while busy, and
on FAILURE a typed reason (:class:`bt_grasp.behaviours.reasons.FailureReason`) plus one sentence.
"""

from bt_grasp.behaviours.library import register_robot_leaves, robot_registry

#: what ``bt-grasp tree`` commands call to add the robot leaves to the built-in nodes
register = register_robot_leaves

__all__ = ["register", "register_robot_leaves", "robot_registry"]
