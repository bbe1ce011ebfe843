"""The campaign workers' episode backend, on today's run composition (cli/session.py).

TEMPORARY home: run composition is moving below cli/ (the episode/session API of issue 10); when it is on
main this backend moves there and campaign workers call it directly. Until then the campaign package stays
free of cli imports: ``bt-grasp eval`` hands :func:`session_backend` to the workers (pickled by reference).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_grasp.campaign.episode import EpisodeOutcome, FinalState
from bt_grasp.campaign.spec import Episode


class SessionBackend:
    """Implements :class:`bt_grasp.campaign.episode.EpisodeBackend`: a fresh physics world per episode (so an
    episode never depends on what ran before it in this process) with the renderer kept warm."""

    def __init__(self) -> None:
        self._keepalive: Any = None

    def warm_up(self) -> None:
        import bt_grasp.behaviours
        import bt_grasp.cli.session  # noqa: F401
        from bt_grasp.sim.warm import RendererKeepalive

        self._keepalive = RendererKeepalive()

    def run(self, episode: Episode, log: Path | None) -> EpisodeOutcome:
        import numpy as np

        from bt_grasp.cli.session import Prepared, RunRequest, execute
        from bt_grasp.geometry import quat_wxyz
        from bt_grasp.recording.jsonable import to_jsonable
        from bt_grasp.sim.oracle import GroundTruthOracle

        request = RunRequest(
            tree=episode.tree_file,
            scene=episode.scene_file,
            seed=episode.seed,
            calibration=episode.calibration_file,
            log=log,
            max_ticks=episode.max_ticks,
            faults=episode.fault_file,
            inject=episode.inject,
            blackboard=episode.blackboard,
            argv=("bt-grasp", "eval", "run", episode.campaign, episode.key),
        )
        prepared = Prepared(request)
        summary, stream = execute(prepared)
        world = prepared.world
        oracle = GroundTruthOracle(world)  # judge-only truth, for the run fingerprint's final object poses
        poses = {}
        for name in oracle.object_names():
            T = oracle.T_world_object(name)
            poses[name] = (*(float(v) for v in T[:3, 3]), *(float(v) for v in quat_wxyz(T)))
        final = FinalState(
            q_rad=tuple(float(v) for v in np.asarray(world.robot.joint_positions())),
            gripper_width_m=float(world.robot.gripper_width_m()),
            object_poses=poses,
        )
        # JSON form (no repr with memory addresses): the same run gives the same text in any process
        blackboard = {k: to_jsonable(v) for k, v in sorted(prepared.tree.blackboard_values().items())}
        return EpisodeOutcome(
            success=summary.success,
            judged_goal=str(summary.judge.get("task", "")),
            tree_status=summary.tree_status,
            failure_reason=summary.reason,
            failed_leaf=summary.failed_leaf,
            ticks=summary.ticks,
            sim_time_s=summary.sim_time_s,
            wall_time_s=summary.wall_time_s,
            retries=summary.retries,
            faults_fired=summary.faults_fired,
            judge=summary.judge,
            stream=stream,
            failures=[{"leaf": summary.failed_leaf, "reason": summary.reason}] if summary.reason else [],
            final=final,
            blackboard=blackboard,
        )


def session_backend() -> SessionBackend:
    return SessionBackend()
