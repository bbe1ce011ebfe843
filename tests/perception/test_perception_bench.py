"""The benchmark's own pieces: seeded scenes are reproducible and valid; yaw error respects symmetry;
the loop runs end to end against a stand-in backend that renders analytic frames."""

from __future__ import annotations

import numpy as np
import pytest
from perception_synth import DEFAULT_T_BASE_CAMERA, Box, render

from bt_grasp.bench.perception import random_scene, run_perception_bench, yaw_error_deg
from bt_grasp.geometry import make_T, rot_z
from bt_grasp.scene.format import Scene


def test_random_scenes_are_seeded_and_valid() -> None:
    a = [random_scene(Scene(), np.random.default_rng(5), i) for i in range(3)]
    b = [random_scene(Scene(), np.random.default_rng(5), i) for i in range(3)]
    assert a == b
    for scene in a:
        assert 2 <= len(scene.objects) <= 4
        assert len({o.color for o in scene.objects}) == len(scene.objects)


def test_yaw_error_symmetry() -> None:
    T = make_T(rot_z(np.deg2rad(10.0)))
    assert yaw_error_deg(np.deg2rad(10.5), T, (0.07, 0.04, 0.05)) == pytest.approx(0.5)
    assert yaw_error_deg(np.deg2rad(-169.0), T, (0.07, 0.04, 0.05)) == pytest.approx(1.0)
    assert yaw_error_deg(np.deg2rad(100.0 - 1.0), T, (0.04, 0.07, 0.05)) == pytest.approx(1.0)  # long side is y
    assert yaw_error_deg(np.deg2rad(-79.0), T, (0.05, 0.05, 0.05)) == pytest.approx(1.0)  # square: 90 deg
    assert yaw_error_deg(0.3, T, (0.02, 0.05)) is None  # cylinder


class _FakeBackend:
    """Places each scene's target alone on an analytic table (red/blue only: the synthetic palette)."""

    def base_scene(self) -> Scene:
        return Scene()

    def capture(self, scene, seed):  # type: ignore[no-untyped-def]
        target = scene.objects[0]
        size = target.size_m if target.shape == "box" else (0.04, 0.04, 0.05)
        box = Box((0.5, 0.02 * (seed % 3)), size, 0.2, (199, 66, 70))
        T = make_T(rot_z(0.2), [box.centre_xy[0], box.centre_xy[1], size[2] / 2])
        return render([box], noise_m=0.001, seed=seed), {target.name: T}

    def calibrate(self, scene, mount, seed, poses):  # type: ignore[no-untyped-def]
        return DEFAULT_T_BASE_CAMERA, {"tsai": (0.0, 0.0)}


def test_bench_loop_with_a_stand_in_backend(monkeypatch: pytest.MonkeyPatch) -> None:
    import bt_grasp.bench.perception as bench

    monkeypatch.setattr(bench, "BENCH_COLORS", ("red",) * 6)  # the stand-in draws every target red
    summary = run_perception_bench(4, 0, backend=_FakeBackend(), calibrate=True)
    assert summary["scenes"] == 4 and summary["detection_rate"] == 1.0
    assert summary["centroid_err_mm_median"] < 3.0
    assert set(summary["calibration"]) == {"eye-to-hand/noise", "eye-to-hand/no_noise", "eye-in-hand/noise",
                                           "eye-in-hand/no_noise"}
