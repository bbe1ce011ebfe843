"""`bt-grasp run ... --live --control`: a run driven from Foxglove (the Parameters and Publish panels of the
control layout; bt_grasp.control.foxglove maps them to the control API). It starts paused, so a viewer sees the
tree before anything moves."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.console import Console

from bt_grasp.errors import InputError

if TYPE_CHECKING:
    from bt_grasp.control.breakpoints import Breakpoint
    from bt_grasp.episode import TickCallback
    from bt_grasp.episode.request import EpisodeRequest
    from bt_grasp.episode.result import EpisodeResult


def remote_control_warning(host: str) -> str:
    return (f"warning: --allow-remote-control: anyone who can reach {host}:PORT can pause, edit and stop this run "
            "(the Foxglove WebSocket protocol has no authentication); see docs/security.md.")


def run_foxglove_control(request: EpisodeRequest, breakpoints: tuple[Breakpoint, ...], *, allow_remote: bool,
                         console: Console, on_tick: tuple[TickCallback, ...] = ()) -> EpisodeResult:
    """Run one episode whose live server takes commands from its viewers."""
    from bt_grasp.control import Controller, check_breakpoints
    from bt_grasp.control.foxglove import FoxgloveControl, is_loopback
    from bt_grasp.episode.episode import Episode
    from bt_grasp.recording.layout import control_layout_path

    if not is_loopback(request.live_host) and not allow_remote:
        raise InputError("--control", f"--live-host {request.live_host} can be reached from other machines and the "
                         "protocol has no authentication; keep a loopback host (127.0.0.1) and tunnel, or add "
                         "--allow-remote-control")
    if not is_loopback(request.live_host):
        console.print(remote_control_warning(request.live_host), highlight=False, markup=False)
    episode = Episode(request)
    check_breakpoints(episode.tree, breakpoints)
    controller = Controller(breakpoints, start_paused=True)
    control = FoxgloveControl(controller, host=request.live_host, allow_remote=allow_remote)

    def serve(url: str) -> None:
        assert episode.live is not None
        episode.live.serve_control(control)
        console.print(f"live control: in Foxglove, Open connection > Foxglove WebSocket > {url}, layout "
                      f"{control_layout_path()}; the run is paused: set run.paused to false (or press Resume)",
                      highlight=False, markup=False)

    episode.on_live.append(serve)
    return episode.run(on_tick=on_tick, controller=controller)
