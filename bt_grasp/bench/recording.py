"""What recording costs: `bench_logging` (writer overhead per tick, bytes per simulated minute) and
`bench_reading` (time to open a long log and build its summary). A bench command calls these.

The synthetic tick is meant to look like a real one at 100 Hz: ``n_nodes`` nodes of which a handful are
ticked (one RUNNING leaf, its ancestors), a 20-entry blackboard of which two entries change, the arm state,
and every ``image_every`` ticks one 640x480 colour image (a smooth rendered-like scene with mild noise,
JPEG) plus its depth image (16UC1).
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from bt_grasp.recording.reader import open_log
from bt_grasp.recording.replay import summary
from bt_grasp.recording.writer import Compression, RunRecorder
from bt_grasp.tree.records import NodeRecord

DT_NS = 10_000_000  # 100 Hz


def _scene(rng: np.random.Generator, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    yy, xx = np.mgrid[0:h, 0:w]
    rgb = np.empty((h, w, 3), np.float64)
    rgb[..., 0] = 90 + 60 * yy / h
    rgb[..., 1] = 100 + 40 * xx / w
    rgb[..., 2] = 120
    for _ in range(5):
        y, x = rng.integers(0, h - 60), rng.integers(0, w - 60)
        rgb[y: y + 50, x: x + 50] = rng.integers(0, 255, 3)
    rgb += rng.normal(0.0, 2.0, rgb.shape)
    depth = (0.6 + 0.3 * yy / h).astype(np.float32)
    depth[rng.random((h, w)) < 0.01] = 0.0
    return np.clip(rgb, 0, 255).astype(np.uint8), depth


def _nodes(tick: int, n_nodes: int) -> list[NodeRecord]:
    """The tick's node records, as the runner hands them over: the root (a Sequence) and its leaves."""
    active = 1 + (tick // 40) % max(1, n_nodes - 1)  # the leaf running now; changes every 40 ticks
    out: list[NodeRecord] = []
    for uid in range(1, n_nodes + 1):
        running = uid in (1, active)
        status = "RUNNING" if running else ("SUCCESS" if uid < active else "IDLE")
        out.append({"uid": uid, "type": "Action", "name": f"N{uid}", "path": f"Root/N{uid}",
                    "kind": "Control" if uid == 1 else "Action", "status": status, "failure_reason": None,
                    "ticked": running, "feedback": f"step {tick % 40}" if uid == active else ""})
    return out


def bench_logging(
    n_ticks: int = 6000, n_nodes: int = 30, image_every: int = 50, image_shape: tuple[int, int] = (480, 640),
    compression: Compression = "zstd", folder: str | Path | None = None,
) -> dict[str, object]:
    """Write a synthetic run and measure. Returns µs per tick (write_tick + flush_tick, mean/p50/p99), ms
    per image pair, file size and MB per simulated minute at 100 Hz, with and without images."""
    rng = np.random.default_rng(0)
    rgb, depth = _scene(rng, *image_shape)
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        path = Path(tmp) / "bench.mcap"
        tick_us: list[float] = []
        image_ms: list[float] = []
        board: dict[str, object] = {f"key{i}": i for i in range(18)}
        image_bytes = 0
        with RunRecorder(path, metadata={"bench": "1"}, compression=compression, handle_signals=False) as rec:
            rec.write_tree_structure(0, {"uid": 1, "type": "Sequence", "name": "Root", "path": "Root",
                                         "kind": "control", "attributes": {}, "children": []})
            for tick in range(n_ticks):
                nodes = _nodes(tick, n_nodes)
                board["counter"] = tick // 10
                board["target_q"] = np.full(6, 0.01 * (tick // 25))
                q = np.sin(0.001 * tick + np.arange(6))
                T = np.eye(4)
                T[:3, 3] = (0.4, 0.0, 0.3 + 1e-4 * tick)
                robot = {"q_rad": q, "qd_rad_s": np.cos(q), "gripper_width_m": 0.08, "T_base_tcp": T}
                t0 = time.perf_counter()
                rec.write_tick(tick, tick * DT_NS, nodes, board, robot)
                rec.flush_tick()
                tick_us.append((time.perf_counter() - t0) * 1e6)
                if image_every and tick % image_every == 0:
                    before = os.path.getsize(path)
                    t1 = time.perf_counter()
                    rec.write_color_image(tick * DT_NS, rgb, "camera_color_optical_frame")
                    rec.write_depth(tick * DT_NS, depth, "camera_color_optical_frame")
                    rec.flush_tick()
                    image_ms.append((time.perf_counter() - t1) * 1e3)
                    image_bytes += os.path.getsize(path) - before  # the pair's own chunk
            size_open = os.path.getsize(path)
        size = os.path.getsize(path)
        minutes = n_ticks / 100.0 / 60.0
    return {
        "n_ticks": n_ticks, "n_nodes": n_nodes, "image_every": image_every, "compression": compression,
        "tick_us_mean": statistics.fmean(tick_us), "tick_us_p50": statistics.median(tick_us),
        "tick_us_p99": float(np.percentile(tick_us, 99)),
        "image_pair_ms_mean": statistics.fmean(image_ms) if image_ms else 0.0,
        "file_bytes": size, "file_bytes_before_close": size_open,
        "mb_per_sim_minute": size / 1e6 / minutes,
        "mb_per_sim_minute_without_images": (size - image_bytes) / 1e6 / minutes,
        "cpu_count": os.cpu_count(),
    }


def bench_reading(n_ticks: int = 10_000, n_nodes: int = 30, folder: str | Path | None = None) -> dict[str, object]:
    """Write an image-less ``n_ticks`` log, then time ``open_log`` + ``summary`` (indexed) and the same
    on a copy without its summary (the linear crash-recovery path)."""
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        path = Path(tmp) / "long.mcap"
        with RunRecorder(path, metadata={"bench": "1"}, handle_signals=False) as rec:
            for tick in range(n_ticks):
                rec.write_tick(tick, tick * DT_NS, _nodes(tick, n_nodes), {"counter": tick // 10},
                               {"q_rad": np.zeros(6), "qd_rad_s": np.zeros(6), "gripper_width_m": 0.08,
                                "T_base_tcp": np.eye(4)})
                rec.flush_tick()
        t0 = time.perf_counter()
        indexed = summary(open_log(path))
        indexed_s = time.perf_counter() - t0
        cut = Path(tmp) / "cut.mcap"
        cut.write_bytes(path.read_bytes()[:-8])
        t0 = time.perf_counter()
        linear = summary(open_log(cut))
        linear_s = time.perf_counter() - t0
        file_bytes = path.stat().st_size
    return {"n_ticks": n_ticks, "indexed_summary_s": indexed_s, "linear_summary_s": linear_s,
            "ticks_indexed": indexed["ticks"], "ticks_linear": linear["ticks"],
            "file_bytes": file_bytes}
