"""The simulated work cell: the only package that imports sapien.

``World`` builds a scene file into a SAPIEN scene; ``SimRobot`` and ``SimCamera`` implement the
interfaces of :mod:`bt_grasp.interfaces`; ``GroundTruthOracle`` is the one place that reads true poses,
for tests, benchmarks and the run summary's judge only.
"""

from bt_grasp.sim.world import World

__all__ = ["World"]
