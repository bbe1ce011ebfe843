"""The simulator side of the perception benchmarks (``bench perception``, ``--noise-sweep``): a fresh world per
scene, the truth from the oracle. Benchmarks may read ground truth; the pipeline they score never does."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.scene.format import DepthNoise, Scene, load_scene


class SimBenchBackend:
    """Implements ``bench.perception.BenchBackend`` and ``bench.noise``'s backend with SAPIEN worlds."""

    def __init__(self, scene_path: Path) -> None:
        self._base = load_scene(scene_path)

    def base_scene(self) -> Scene:
        return self._base

    def capture(self, scene: Scene, seed: int) -> tuple[RGBDFrame | None, dict[str, Mat4]]:
        from bt_grasp.sim.oracle import GroundTruthOracle
        from bt_grasp.sim.world import World

        world = World(scene, seed, camera_mount=Mount.EYE_TO_HAND)
        world.step(world.steps_per_tick * 10)
        oracle = GroundTruthOracle(world)
        return world.camera.capture(), {name: oracle.T_base_object(name) for name in oracle.object_names()}

    def capture_levels(self, scene: Scene, seed: int, noises: Sequence[DepthNoise]
                       ) -> tuple[list[RGBDFrame | None], dict[str, Mat4]]:
        from bt_grasp.sim.oracle import GroundTruthOracle
        from bt_grasp.sim.render_keeper import keep_renderer_warm
        from bt_grasp.sim.world import World

        # a world per scene beside a renderer kept warm for the sweep: its first picture costs ~0.1 s
        keep_renderer_warm()
        world = World(scene, seed, camera_mount=Mount.EYE_TO_HAND)
        world.step(world.steps_per_tick * 10)
        oracle = GroundTruthOracle(world)
        frames: list[RGBDFrame | None] = list(world.camera.capture_variants(noises, seed))
        return frames, {name: oracle.T_base_object(name) for name in oracle.object_names()}

    def calibrate(self, scene: Scene, mount: str, seed: int, poses: int) -> tuple[Mat4, dict[str, tuple[float, float]]]:
        from bt_grasp.episode.calibration import calibrate_in_sim

        result = calibrate_in_sim(scene, mount, seed, poses)
        return result.run.solution.X, result.true_error_per_method
