"""`bt-grasp scene render`: build a scene and write what the camera sees."""

from __future__ import annotations

import json
import time
from pathlib import Path

import typer

from bt_grasp.files.output_files import make_output_folder, write_output_file
from bt_grasp.interfaces import Mount

scene_app = typer.Typer(help="Inspect scene files.", no_args_is_help=True)


@scene_app.command("validate")
def validate(scene: Path = typer.Argument(..., help="Scene YAML file.")) -> None:
    """Check a scene file as `bt-grasp run` checks it (its calibration file among them) and print a one-line
    summary; a note when a run with no --goal or --color would refuse it."""
    from bt_grasp.cli.text_width import wrap
    from bt_grasp.episode.episode import check_goal
    from bt_grasp.episode.request import run_blackboard
    from bt_grasp.errors import InputError
    from bt_grasp.perception.calibration_file import calibration_for_scene
    from bt_grasp.scene.format import load_scene
    from bt_grasp.scene.run_goal import goal_for_run

    config = load_scene(scene)
    calibration_for_scene(config, scene, None)  # what `run` refuses: the file it names missing, another mount
    note = ""
    try:  # the goal a run with no --goal/--color judges: the scene's, else a pick of its default colour
        check_goal(goal_for_run(config, run_blackboard()), config, scene, given=False)
    except InputError as exc:
        if config.goal is not None:
            raise  # the scene's own goal cannot be judged: the file is wrong, whatever the options
        note = "\n" + wrap(f"note: `bt-grasp run` with no --goal or --color refuses it: {exc.message}")
    typer.echo(f"{scene}: ok ({len(config.objects)} objects, camera {config.camera.mount}){note}")


@scene_app.command("render")
def render(
    scene: Path = typer.Argument(..., help="Scene YAML file."),
    seed: int = typer.Option(0, "--seed", help="Seed for object poses and camera noise."),
    out: Path = typer.Option(Path("out"), "--out", help="Folder to write color.png, depth.png, camera.json."),
    mount: Mount | None = typer.Option(None, "--mount", help="Where the camera is (default: the scene's)."),
) -> None:
    """Render one RGB-D capture: color.png, a colour-mapped depth.png and camera.json."""
    import cv2
    import numpy as np

    from bt_grasp.scene.format import load_scene

    config = load_scene(scene)
    from bt_grasp.sim.world import World

    t0 = time.perf_counter()
    world = World(config, seed, camera_mount=mount, source=scene)
    build_s = time.perf_counter() - t0
    world.step(world.steps_per_tick * 10)  # let objects settle for 0.1 s
    t1 = time.perf_counter()
    frame = world.camera.capture()
    capture_s = time.perf_counter() - t1
    assert frame is not None
    make_output_folder(out, "--out")
    color_bgr = cv2.cvtColor(frame.color, cv2.COLOR_RGB2BGR)
    write_output_file(out / "color.png", cv2.imencode(".png", color_bgr)[1].tobytes(), "--out")
    depth = frame.depth_m
    valid = depth > 0
    lo, hi = (float(np.percentile(depth[valid], 1)), float(np.percentile(depth[valid], 99))) if valid.any() else (0, 1)
    scaled = np.clip((depth - lo) / max(hi - lo, 1e-6), 0, 1)
    colored = cv2.applyColorMap((255 - scaled * 255).astype(np.uint8), cv2.COLORMAP_TURBO)
    colored[~valid] = 0
    write_output_file(out / "depth.png", cv2.imencode(".png", colored)[1].tobytes(), "--out")
    cam = config.camera
    info = {
        "scene": str(scene),
        "seed": seed,
        "mount": frame.mount,
        "intrinsics": frame.intrinsics.to_dict(),
        "model": cam.model,
        "depth_range_m": [lo, hi],
        "depth_invalid_fraction": float(1.0 - valid.mean()),
        "mount_config": (cam.eye_to_hand if frame.mount == Mount.EYE_TO_HAND else cam.eye_in_hand).model_dump(),
        "stamp_ns": frame.stamp_ns,
    }
    write_output_file(out / "camera.json", json.dumps(info, indent=2) + "\n", "--out")
    typer.echo(f"wrote {out / 'color.png'}, {out / 'depth.png'}, {out / 'camera.json'}")
    typer.echo(f"scene built in {build_s:.2f} s, capture {capture_s:.2f} s (first capture compiles shaders)")


def register(app: typer.Typer) -> None:
    app.add_typer(scene_app, name="scene")
