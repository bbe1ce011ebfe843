"""`bt-grasp camera record|compare`: RealSense recordings with pyrealsense2's own recorder, from the simulator or a
live device, and recordings checked against the simulator they were made from."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from bt_grasp.detector.kinds import DetectorKind
from bt_grasp.interfaces import Mount

camera_app = typer.Typer(help="RealSense recordings: record from a scene or a device, compare with the simulator.",
                         no_args_is_help=True)


@camera_app.command("record")
def record(
    out: Path = typer.Option(..., "--out", help="The recording to write (FILE.db3)."),
    scene: Path | None = typer.Option(None, "--scene", help="Record this scene's simulated D435."),
    seed: int = typer.Option(0, "--seed", help="The scene's seed."),
    frames: int = typer.Option(1, "--frames", min=1, help="Frames to record from the scene."),
    mount: Mount | None = typer.Option(None, "--mount", help="Where the scene's camera is (default: the scene's)."),
    device: str | None = typer.Option(None, "--device", help="Record a live device instead: its serial number, or "
                                      "none for the only one connected."),
    seconds: float = typer.Option(5.0, "--seconds", min=0.1, help="How long to record a live device, s."),
) -> None:
    """Write a RealSense recording (.db3) through pyrealsense2's recorder: a scene's simulated D435 (depth as its
    depth imager sees it; an eye-in-hand camera's tool poses beside it in FILE.poses.jsonl), or a live device."""
    from bt_grasp.errors import InputError
    from bt_grasp.sensing.record_scene import check_recording_output, record_scene

    if (scene is None) == (device is None):
        raise InputError("camera record", "give --scene SCENE (a simulated camera) or --device [SERIAL] (a live "
                         "one), not both and not neither")
    if scene is not None:
        done = record_scene(scene, seed, out, frames, mount)
        poses = f"; tool poses in {done.poses}" if done.poses else ""
        typer.echo(f"wrote {done.path}: {done.frames} frame(s) of {scene} seed {seed} ({done.mount.value}), device "
                   f"time {done.first_stamp_ns / 1e9:.3f}-{done.last_stamp_ns / 1e9:.3f} s{poses}")
        return
    from bt_grasp.hardware.live_record import record_device

    check_recording_output(out)
    live = record_device(out, seconds, device or None)
    typer.echo(f"wrote {live.path}: {live.frame_sets} frame sets of RealSense {live.serial} in {live.seconds:.1f} s")


@camera_app.command("compare")
def compare(
    scenes: list[Path] = typer.Option(
        [Path("scenes/tabletop.yaml"), Path("scenes/clutter.yaml"), Path("scenes/household.yaml"),
         Path("scenes/eye_in_hand.yaml")], "--scene", help="Scenes to record and compare (repeatable)."),
    seeds: int = typer.Option(3, "--seeds", min=1, help="Seeds per scene, from --first-seed."),
    first_seed: int = typer.Option(0, "--first-seed"),
    frames: int = typer.Option(1, "--frames", min=1, help="Frames recorded per case."),
    detector: DetectorKind = typer.Option(DetectorKind.LEARNED, "--detector", help="What finds the objects."),
    folder: Path | None = typer.Option(None, "--keep", help="Keep the recordings in this folder."),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Record each scene and seed with `camera record`, perceive the recording and the scene (`perceive REC` vs
    `perceive --scene`), and compare: detections, classes, centroids, the top grasp, and the aligned depth against
    the simulator's own colour-aligned depth (with and without the noise model). A developer check."""
    from bt_grasp.sensing.compare import compare_cases

    report = compare_cases(scenes, range(first_seed, first_seed + seeds), frames, detector, folder)
    if as_json:
        typer.echo(json.dumps(report.as_json()))
    else:
        for line in report.lines():
            typer.echo(line)
    raise typer.Exit(0 if report.all_pass else 1)


def register(app: typer.Typer) -> None:
    app.add_typer(camera_app, name="camera")
