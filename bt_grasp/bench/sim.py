"""Benchmark of the simulated cell: scene build time, RGB-D capture time, physics speed."""

from __future__ import annotations

import statistics
import time
from pathlib import Path
from typing import TypedDict

import numpy as np

from bt_grasp.process.environment import machine_description
from bt_grasp.scene.format import load_scene
from bt_grasp.sim.world import World


class SimBench(TypedDict):
    """``run_sim_bench``'s figures."""

    machine: str
    scene_build_s_first: float
    scene_build_s_median: float
    first_capture_s: float
    render_ms_median: float
    capture_ms_median: float
    physics_steps_per_s: int
    sim_s_per_wall_s: float
    timestep_s: float


def run_sim_bench(scene_path: str | Path, captures: int = 20, physics_seconds: float = 10.0) -> SimBench:
    """Measure build, capture and physics speed on this machine; returns a JSON-able dict."""
    config = load_scene(scene_path)
    t0 = time.perf_counter()
    world = World(config, seed=0, source=scene_path)
    build_first_s = time.perf_counter() - t0
    builds = []
    for seed in range(1, 4):
        t = time.perf_counter()
        World(config, seed=seed, source=scene_path)
        builds.append(time.perf_counter() - t)
    t = time.perf_counter()
    world.camera.capture()
    first_capture_s = time.perf_counter() - t
    capture_ms, render_ms = [], []
    for _ in range(captures):
        t = time.perf_counter()
        world.camera.render_true()
        render_ms.append((time.perf_counter() - t) * 1e3)
        t = time.perf_counter()
        world.camera.capture()
        capture_ms.append((time.perf_counter() - t) * 1e3)
    # the arm swings through a joint-space sine with no rendering
    robot = world.robot
    home = np.asarray(config.robot.home_q_rad)
    ticks = int(physics_seconds * config.physics.control_rate_hz)
    t = time.perf_counter()
    for i in range(ticks):
        phase = 2 * np.pi * i / config.physics.control_rate_hz / 4.0
        robot.set_joint_targets(home + 0.4 * np.sin(phase) * np.array([1, 0.5, -0.5, 0.5, 1, 1]))
        world.step_tick()
    wall = time.perf_counter() - t
    steps = ticks * world.steps_per_tick
    return {
        "machine": machine_description(),
        "scene_build_s_first": round(build_first_s, 3),
        "scene_build_s_median": round(statistics.median(builds), 3),
        "first_capture_s": round(first_capture_s, 2),
        "render_ms_median": round(statistics.median(render_ms), 1),
        "capture_ms_median": round(statistics.median(capture_ms), 1),
        "physics_steps_per_s": round(steps / wall),
        "sim_s_per_wall_s": round(physics_seconds / wall, 1),
        "timestep_s": config.physics.timestep_s,
    }
