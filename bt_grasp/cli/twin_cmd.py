"""`bt-grasp twin`: serve a scene's simulated cell as a UR controller (with a Robotiq gripper and a camera) until
Ctrl-C, in real time. The twin itself is ``bt_grasp.sim.twin``; docs/twin.md is the guide."""

from __future__ import annotations

import sys
import threading
from enum import StrEnum
from pathlib import Path

import typer


class ModelChoice(StrEnum):
    """`twin --model`: the controllers a twin serves as (``bt_grasp.sim.twin.config.MODELS``)."""

    ur5 = "ur5"


class GripperChoice(StrEnum):
    """`twin --gripper`: the gripper models (``bt_grasp.cell.grippers.GripperName``)."""

    robotiq_2f85 = "robotiq-2f85"
    bt_grasp = "bt-grasp"


def remote_warning(host: str) -> str:
    return (
        f"warning: --host {host} serves a robot controller to anyone who can reach these ports: RTDE, the dashboard "
        "and the script port have no authentication, and whoever connects can move the simulated arm and stop it. "
        "To reach the twin from another machine, keep the default 127.0.0.1 and tunnel (ssh -L 30004:127.0.0.1:30004 "
        "... this-host); see docs/twin.md."
    )


def twin(
    scene: Path = typer.Option(..., "--scene", help="Scene YAML file: the cell to serve."),
    host: str = typer.Option("127.0.0.1", "--host", help="Address to serve on (loopback by default; twins side by "
                             "side need separate loopback addresses, 127.0.0.2, ...: ur_rtde's ports are fixed)."),
    model: ModelChoice = typer.Option(ModelChoice.ur5, "--model", help="The controller to serve as."),
    seed: int = typer.Option(0, "--seed", help="Seed of the scene's object poses and camera noise."),
    gripper: GripperChoice = typer.Option(GripperChoice.robotiq_2f85, "--gripper",
                                          help="The simulated gripper (its socket is a Robotiq 2F-85's)."),
    write_cell: Path | None = typer.Option(None, "--write-cell", help="Write the cell file of this twin's cell "
                                           "(for `--cell`) before serving."),
    unlock_delay: float = typer.Option(5.0, "--unlock-delay", min=0.0, max=60.0,
                                       help="Seconds before a protective stop may be unlocked (a UR's: 5)."),
    camera_hz: float = typer.Option(0.0, "--camera-hz", min=0.0, max=60.0,
                                    help="Render the camera continuously at this rate (0: on request)."),
    control_port: int = typer.Option(30100, "--control-port", min=1024, max=65535,
                                     help="The twin's own port (faults, judge, camera)."),
    camera_port: int = typer.Option(30101, "--camera-port", min=1024, max=65535,
                                    help="The twin's camera port (a run's frames, as a D435 delivers them)."),
    board: bool = typer.Option(False, "--board", help="Screw the ChArUco calibration board to the gripper (for "
                               "`bt-grasp calibrate --cell`); the cell file then names it."),
    realtime: bool = typer.Option(True, "--realtime/--no-realtime", help="Ask for real-time scheduling of the "
                                  "controller's cycle, as a robot controller has (refused without the permission)."),
) -> int:
    """Serve a scene's simulated cell to the unmodified ur_rtde library and a Robotiq client, in real time."""
    import logging
    import signal

    from bt_grasp.errors import InputError
    from bt_grasp.files.hosts import is_loopback
    from bt_grasp.scene.format import load_scene

    config_scene = load_scene(scene)  # a bad scene file fails here with file:line, before anything starts
    if write_cell is not None:
        from bt_grasp.files.output_files import check_output_file

        check_output_file(write_cell, "--write-cell", example="twin.cell.yaml", inputs=(scene,))
    if not is_loopback(host):
        typer.echo(remote_warning(host), err=True)
    logging.basicConfig(level=logging.INFO, format="twin: %(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    sys.setswitchinterval(0.001)  # the controller's thread gets the interpreter within 1 ms of wanting it
    from bt_grasp.cell.grippers import GripperName
    from bt_grasp.sim.twin.config import MODELS, TwinConfig
    from bt_grasp.sim.twin.twin import Twin, check_ports_free

    def taken(exc: OSError) -> InputError:
        return InputError("--host", f"cannot serve on {exc.strerror or exc} (another twin or a robot driver holds "
                          "the port; give another loopback address such as 127.0.0.2)")

    try:
        check_ports_free(host, control_port, camera_port)
    except OSError as exc:
        raise taken(exc) from None

    config = TwinConfig(host=host, model=MODELS[model.value], gripper=GripperName(gripper.value),
                        unlock_delay_s=unlock_delay, control_port=control_port, camera_port=camera_port,
                        board=board, realtime_priority=10 if realtime else None)
    the_twin = Twin(scene, config, seed)
    if write_cell is not None:
        from bt_grasp.sim.twin.cell_writer import write_cell as write

        write(config_scene, scene, config, write_cell, the_twin.board)
        typer.echo(f"cell file: {write_cell}")
    stop = threading.Event()  # set before the ports open: a Ctrl-C while the twin starts stops it cleanly too
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    try:
        the_twin.start()
    except OSError as exc:
        the_twin.stop()
        raise taken(exc) from None
    if camera_hz > 0:
        the_twin.camera("on", camera_hz)
    typer.echo(f"twin of {scene} serving {model.value} on {host}: RTDE 30004, dashboard 29999, script 30003, "
               f"gripper 63352, control {control_port}, camera {camera_port} (Ctrl-C stops)")
    sys.stdout.flush()
    try:
        while not stop.wait(0.5):
            if the_twin.loop.error is not None:
                break
    finally:
        the_twin.stop()
    if the_twin.loop.error is not None:
        raise typer.Exit(1)
    return 0


def register(app: typer.Typer) -> None:
    app.command("twin")(twin)
