"""Issue 45's 'Done when' 2 and 3, tick by tick on the simulator, at 30 cm/s with the perception latency on:

* the belt tracker's prediction 0.5 s ahead, from the fifth detection on, against where the object really is then
  (the simulator's truth, read through the oracle here in the test only);
* the intercept chosen is one the arm reaches, and the tool moves with the belt at contact (within 2 cm/s);
* a frame's detections reach the tracker exactly the declared latency after the frame (0.1 s: ten ticks);
* a chance lost (the object let go too far downstream) ends with INTERCEPT_MISSED within the ride, not a stall;
* the same seed twice gives the same tick stream (fingerprints of two logs).

One episode serves the first three (a module fixture)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes/conveyor.yaml"
TREE = REPO / "trees/pick_from_conveyor.xml"
SEED = 2
HORIZON_S = 0.5

pytestmark = pytest.mark.sim


@dataclass
class Watched:
    """What the hooks saw: predictions made (due time, base-frame position, detections so far), the true
    positions of every object per tick, the tcp per tick, frames handed over (frame time, hand-over time), and
    the intercept's phase per tick."""

    predictions: list[tuple[float, np.ndarray]] = field(default_factory=list)
    truth: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)
    tcp: dict[int, np.ndarray] = field(default_factory=dict)
    handed: list[tuple[float, float]] = field(default_factory=list)
    phases: dict[int, str] = field(default_factory=dict)
    plans: list[Any] = field(default_factory=list)
    result: Any = None
    latency_s: float = 0.0
    belt_speed_m_s: float = 0.0


def _tick(t_s: float) -> int:
    return round(t_s * 100)


@pytest.fixture(scope="module")
def watched() -> Watched:
    from bt_grasp.behaviours.belt import TrackOnBelt
    from bt_grasp.behaviours.belt_watch import BeltWatch
    from bt_grasp.behaviours.intercept import InterceptPick
    from bt_grasp.episode import Episode, EpisodeRequest
    from bt_grasp.sim.oracle import GroundTruthOracle

    seen = Watched()
    original_step = BeltWatch.step

    def step(self: BeltWatch, leaf: Any, rate_hz: float, look: bool = True) -> list[Any]:
        before = list(self._in_flight)
        out = original_step(self, leaf, rate_hz, look)
        after = set(map(id, self._in_flight))
        seen.handed.extend((f.t_s, leaf.now_s()) for f in before if id(f) not in after)
        return out

    mp = pytest.MonkeyPatch()
    mp.setattr(BeltWatch, "step", step)
    try:
        episode = Episode(EpisodeRequest(tree=TREE, scene=SCENE, seed=SEED))
        oracle = GroundTruthOracle(episode.world)
        seen.latency_s = episode.scene.latency_s
        seen.belt_speed_m_s = float(episode.scene.fixtures[0].speed_m_s)  # type: ignore[union-attr]

        def on_tick(tick: int, tree: Any) -> None:
            now = episode.world.now_ns() * 1e-9
            k = _tick(now)
            seen.truth[k] = {n: oracle.T_base_object(n)[:3, 3].copy() for n in oracle.object_names()}
            seen.tcp[k] = oracle.T_world_tcp()[:3, 3].copy()
            for node in tree.nodes():
                if node.status.name != "RUNNING":
                    continue
                if isinstance(node, TrackOnBelt):
                    tracks = node.watch.tracks
                elif isinstance(node, InterceptPick):
                    tracks = [node.track]
                    seen.phases[k] = node._phase
                    if node._approach is not None and (not seen.plans or seen.plans[-1] is not node._approach):
                        seen.plans.append(node._approach)
                else:
                    continue
                for track in tracks:
                    if track.detections >= 5:
                        seen.predictions.append((now + HORIZON_S, track.predict(now + HORIZON_S).position_m))

        seen.result = episode.run([on_tick])
    finally:
        mp.undo()
    return seen


def test_the_pick_succeeds_by_physics(watched: Watched) -> None:
    assert watched.result.success, watched.result


def test_the_trackers_prediction_half_a_second_ahead_is_within_5_mm_of_the_truth(watched: Watched) -> None:
    grasp_tick = min(k for k, p in watched.phases.items() if p == "close")
    errors = []
    for due_s, predicted in watched.predictions:
        k = _tick(due_s)
        if k not in watched.truth or k >= grasp_tick:  # after the episode, or once the fingers touch it
            continue
        truths = watched.truth[k]
        # the object predicted: the one nearest (objects are 35 cm or more apart on the belt)
        nearest = min(truths.values(), key=lambda p: float(np.linalg.norm(p[:2] - predicted[:2])))
        errors.append(float(np.linalg.norm(nearest[:2] - predicted[:2])))
    assert len(errors) >= 20
    assert max(errors) <= 0.005, f"median {np.median(errors) * 1e3:.1f} mm, max {max(errors) * 1e3:.1f} mm"


def test_the_intercept_is_reached_and_the_tool_moves_with_the_belt_at_contact(watched: Watched) -> None:
    from bt_grasp.motion.kinematics import KinematicModel  # noqa: F401  (the approach's q is the plan's IK)

    assert watched.plans, "an intercept was planned"
    final = watched.plans[-1]
    # reachable: the trajectory ends at the planned configuration at the planned time
    q_end = np.asarray(final.trajectory.at_time(final.trajectory.duration)[0])
    assert np.allclose(q_end, final.q_arrive, atol=1e-6)
    # the tool's true velocity at contact (the tick the fingers start closing), by a central difference
    close_tick = min(k for k, p in watched.phases.items() if p == "close")
    v = (watched.tcp[close_tick + 1] - watched.tcp[close_tick - 1]) / 0.02
    belt = np.array([0.0, watched.belt_speed_m_s, 0.0])  # the belt runs along +y
    assert float(np.linalg.norm(v - belt)) <= 0.02, f"tool {v} m/s, belt {belt} m/s"


def test_a_frames_detections_reach_the_tracker_exactly_the_latency_after_the_frame(watched: Watched) -> None:
    assert watched.latency_s == pytest.approx(0.1)
    assert len(watched.handed) > 10
    ticks = {_tick(handed) - _tick(taken) for taken, handed in watched.handed}
    assert ticks == {_tick(watched.latency_s)}  # ten ticks of 10 ms, never sooner, never later


MISSED_TREE = """<?xml version="1.0"?>
<root BTCPP_format="4" main_tree_to_execute="Missed">
  <BehaviorTree ID="Missed">
    <Sequence>
      <LoadCalibration file="{calibration_file}"/>
      <OpenGripper/>
      <BeltWaitPose belt="belt"/>
      <TrackOnBelt belt="belt" target="{belt_target}"/>
      <Sleep msec="2500"/>
      <InterceptPick name="intercept" target="{belt_target}" lift="0.1"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def test_a_lost_chance_ends_with_intercept_missed_not_a_stall(tmp_path: Path) -> None:
    from bt_grasp.episode import Episode, EpisodeRequest

    tree = tmp_path / "missed.xml"
    tree.write_text(MISSED_TREE)
    # the object is handed over, then the tree sleeps 2.5 s (75 cm of belt): no intercept is left
    result = Episode(EpisodeRequest(tree=tree, scene=SCENE, seed=SEED, max_ticks=1500)).run()
    assert not result.success
    assert result.reason == "INTERCEPT_MISSED", result
    assert result.failed_leaf == "intercept"
    assert result.ticks < 1500


@pytest.mark.slow
def test_the_same_seed_gives_the_same_tick_stream_with_latency_on(tmp_path: Path) -> None:
    from bt_grasp.episode import EpisodeRequest, run_episode
    from bt_grasp.recording.fingerprint import fingerprint_of_log
    from bt_grasp.recording.reader import open_log

    logs = [tmp_path / f"belt_{k}.mcap" for k in (1, 2)]
    for log in logs:
        assert run_episode(EpisodeRequest(tree=TREE, scene=SCENE, seed=SEED, log=log)).success
    a, b = (fingerprint_of_log(open_log(log)) for log in logs)
    assert open_log(logs[0]).metadata["perception_latency_s"] == "0.1"
    assert a.first_difference(b) is None
    assert a.digest == b.digest
