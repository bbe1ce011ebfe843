"""How `bt-grasp perceive` prints: a header saying which frame everything is in, then a table a frame."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from bt_grasp.sensing.report import FrameReport, ObjectReport


def print_header(source: str, frame_id: str, calibration: Path | None, detector: str) -> None:
    typer.echo(f"source: {source}; detector: {detector}")
    if frame_id == "base_link":
        given = f" ({calibration})" if calibration else " (the scene's)"
        typer.echo(f"frame: base_link, through the calibration{given}; grasps ranked as PlanGrasp tries them from "
                   "the home pose")
    else:
        typer.echo(f"frame: {frame_id} -- no calibration: every position is in the camera frame, the table found "
                   "in each frame gives 'up', and grasps are not checked for the arm's reach")


def _fmt(values: tuple[float, ...] | list[float], scale: float = 1.0, digits: int = 3) -> str:
    return " ".join(f"{v * scale:.{digits}f}" for v in values)


def _approach(report: ObjectReport, frame_id: str) -> str:
    """The best grasp's approach from straight down, degrees (only the base frame knows which way is down)."""
    if not report.grasps or frame_id != "base_link":
        return "-"
    z = report.grasps[0].T_frame_tcp[:3, 2]
    return f"{math.degrees(math.acos(max(-1.0, min(1.0, -float(z[2]))))):.0f}"


def print_frame(report: FrameReport) -> None:
    stamp = f"{report.stamp_ns / 1e9:.6f} s" if report.stamp_ns >= 0 else "-"
    typer.echo(f"\nframe {report.index} (device time {stamp}): {report.status}: {report.message}")
    if not report.objects:
        return
    typer.echo(f"  {'#':>2} {'object':14} {'shape':13} {'centre x y z (m)':24} {'size l w h (mm)':16} {'yaw':>6} "
               f"{'grasps':>6}  {'best grasp x y z (m)':24} {'tilt':>4} {'width':>6}")
    for o in report.objects:
        best = o.grasps[0] if o.grasps else None
        grasp = _fmt(best.position_m) if best else f"none ({o.grasp_status})"
        width = f"{best.width_m * 1000:.0f}mm" if best else "-"
        name = (o.class_name and f"{o.class_name} {o.class_score:.2f}") or o.label
        typer.echo(f"  {o.index:>2} {name:14} {o.shape_class:13} {_fmt(o.centroid_m):24} "
                   f"{_fmt(o.size_m, 1000, 0):16} {o.yaw_deg:6.1f} {len(o.grasps):>6}  {grasp:24} "
                   f"{_approach(o, report.frame_id):>4} {width:>6}")
