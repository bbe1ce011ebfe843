"""The shipped task suite: each task is a tree file plus a scene file that declares its goal."""

from bt_grasp.tasks.suite import TASKS, Task, run_task_bench

__all__ = ["TASKS", "Task", "run_task_bench"]
