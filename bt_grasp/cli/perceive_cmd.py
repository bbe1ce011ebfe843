"""`bt-grasp perceive SOURCE`: the perception pipeline (objects, boxes, classes, ranked grasps; no motion) on the
frames of a RealSense recording, a live RealSense device or a simulated scene; a table a frame, or JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from bt_grasp.detector.kinds import DetectorKind
from bt_grasp.interfaces import Mount

if TYPE_CHECKING:
    from bt_grasp.hardware.realsense_settings import RealSenseSettings
    from bt_grasp.sensing.report import FrameReport


def camera_settings(filters: str, preset: Path | None, timeout_ms: int) -> RealSenseSettings:
    """The RealSense settings of the command line's --filters, --preset and --timeout-ms."""
    from bt_grasp.hardware.realsense_settings import RealSenseSettings, parse_filters

    return RealSenseSettings(filters=parse_filters(filters), preset=preset, timeout_ms=timeout_ms)


def perceive(
    source: Path | None = typer.Argument(None, help="A RealSense recording (.db3, or a ROS 1 .bag)."),
    device: str | None = typer.Option(None, "--device", help="A live RealSense device: its serial number, or none "
                                      "for the only one connected."),
    scene: Path | None = typer.Option(None, "--scene", help="A scene file: its simulated D435, read through "
                                      "pyrealsense2 as a live device."),
    seed: int = typer.Option(0, "--seed", help="The run's seed: the scene's draw (with --scene) and, for any source, "
                             "the streams perception, grasp sampling and IK draw from, as `run --seed` does."),
    mount: Mount | None = typer.Option(None, "--mount", help="Where the scene's camera is (default: the scene's)."),
    calibration: Path | None = typer.Option(None, "--calibration", help="Hand-eye calibration: results in the base "
                                            "frame (a scene's own by default); without one, in the camera frame."),
    detector: DetectorKind = typer.Option(DetectorKind.GEOMETRIC, "--detector", help="What finds the objects."),
    frames: int | None = typer.Option(None, "--frames", min=1, help="Frames to perceive (default: all of a "
                                      "recording, one of a device or scene)."),
    log: Path | None = typer.Option(None, "--log", help="Write an MCAP log Foxglove shows (pictures, cloud, "
                                    "detections, grasps)."),
    filters: str = typer.Option("", "--filters", help="Depth post-processing: spatial,temporal,hole-filling."),
    preset: Path | None = typer.Option(None, "--preset", help="A RealSense Viewer preset (JSON) for a live device."),
    timeout_ms: int = typer.Option(1000, "--timeout-ms", min=1, help="A frame later than this is dropped."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object instead of tables."),
) -> None:
    """Run the perception pipeline on each frame of SOURCE (a recording), --device [SERIAL] or --scene S --seed N
    and print a table a frame: objects, their boxes and classes, and ranked grasps (no motion). Without a
    calibration everything is in the camera frame."""
    from bt_grasp.files.output_files import check_output_file
    from bt_grasp.sensing.perceive_run import PerceiveRequest, run_perceive
    from bt_grasp.sensing.source_spec import choose_source

    spec = choose_source(source, device, scene, seed, mount)
    if log is not None:
        check_output_file(log, "--log", example="perceive.mcap")
    request = PerceiveRequest(spec, calibration, detector, frames, log, camera_settings(filters, preset, timeout_ms),
                              seed=seed)
    if as_json:
        summary = run_perceive(request)
        typer.echo(json.dumps(summary.as_json()))
        return
    from bt_grasp.cli.perceive_table import print_frame, print_header

    printed = [False]

    def show(report: FrameReport) -> None:
        if not printed[0]:
            print_header(spec.describe(), report.frame_id, calibration, detector.value)
            printed[0] = True
        print_frame(report)

    summary = run_perceive(request, show)
    if log is not None:
        typer.echo(f"wrote {log}")
    if not summary.reports:
        typer.echo("no frame")


def register(app: typer.Typer) -> None:
    app.command("perceive")(perceive)
