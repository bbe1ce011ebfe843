"""The run summary's judge: did the task succeed, by physics? Reads the oracle; never used by the pipeline."""

from __future__ import annotations

from dataclasses import dataclass

from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import World


@dataclass(frozen=True)
class Judgement:
    """What the simulator's ground truth says about the end of a run (labelled as the judge's view)."""

    object_name: str | None
    object_lift_m: float  # rise of the lifted object's centre since the start of the run
    in_gripper: bool
    lifted_objects: tuple[str, ...]
    success: bool


class Judge:
    """Scores a pick: the target is above the table by at least the lift height and between the fingers."""

    def __init__(self, world: World) -> None:
        self._world = world
        self._oracle = GroundTruthOracle(world)
        self._start_z = {n: self._oracle.T_world_object(n)[2, 3] for n in self._oracle.object_names()}

    def judge(self, lift_height_m: float, target: str | None = None) -> Judgement:
        rises = {n: float(self._oracle.T_world_object(n)[2, 3] - z) for n, z in self._start_z.items()}
        lifted = tuple(n for n, r in rises.items() if r > 0.02)
        name = target if target is not None else (max(rises, key=lambda n: rises[n]) if rises else None)
        if name is None:
            return Judgement(None, 0.0, False, lifted, False)
        rise = rises[name]
        held = self._oracle.object_in_gripper(name)
        return Judgement(name, rise, held, lifted, bool(held and rise >= lift_height_m - 0.01))

    def objects_in_workspace(self) -> tuple[str, ...]:
        """Objects still standing in the scene's work area (for clear-the-table tasks)."""
        ws = self._world.config.workspace
        inside = []
        for name in self._oracle.object_names():
            x, y = self._oracle.T_world_object(name)[:2, 3]
            if ws.x_m[0] <= x <= ws.x_m[1] and ws.y_m[0] <= y <= ws.y_m[1]:
                inside.append(name)
        return tuple(inside)
