"""A run driven from Foxglove (``run --live --control``): episodes whose live server takes commands from its
viewers (the Parameters and Publish panels of the control layout; ``bt_grasp.foxglove.control`` maps them to
the control API). It starts paused, so a viewer sees the tree before anything moves; a restart from a viewer
runs the next episode on the same port (logs ``run-2.mcap``, ...)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.errors import InputError

if TYPE_CHECKING:
    from bt_grasp.control.breakpoints import Breakpoint
    from bt_grasp.episode import TickCallback
    from bt_grasp.episode.episode import Episode
    from bt_grasp.episode.request import EpisodeRequest
    from bt_grasp.episode.result import EpisodeResult
    from bt_grasp.foxglove.control import FoxgloveControl

#: prints one line for the user (the command line decides how)
Say = Callable[[str], None]


def remote_control_warning(host: str) -> str:
    return (f"warning: --allow-remote-control: anyone who can reach {host}:PORT can pause, edit and stop this run "
            "(the Foxglove WebSocket protocol has no authentication); see docs/security.md.")


def run_foxglove_control(request: EpisodeRequest, breakpoints: tuple[Breakpoint, ...], *, allow_remote: bool,
                         say: Say, on_tick: tuple[TickCallback, ...] = (),
                         layout_folder: Path | None = None, control_files: Path | None = None) -> EpisodeResult:
    """Run an episode whose live server takes commands from its viewers (and, after a restart from them, the
    next one: same port, logs run-2.mcap, ...); returns the last episode's result. ``layout_folder``: where the
    layout goes when the run has no log (the caller removes it); ``control_files``: the folder a viewer's file
    names must lie in (``--control-files``; None: no file may be named)."""
    from bt_grasp.control import Controller, SeedPolicy, check_breakpoints, parse_breakpoint
    from bt_grasp.episode.episode import Episode
    from bt_grasp.files.hosts import is_loopback
    from bt_grasp.foxglove.control import FoxgloveControl

    if not is_loopback(request.live_host) and not allow_remote:
        raise InputError("--control", f"--live-host {request.live_host} can be reached from other machines and the "
                         "protocol has no authentication; keep a loopback host (127.0.0.1) and tunnel, or add "
                         "--allow-remote-control")
    if not is_loopback(request.live_host):
        say(remote_control_warning(request.live_host))
    first = Episode(request)  # bad input stops here
    check_breakpoints(first.tree, breakpoints)
    number, seed = 0, request.seed
    while True:
        episode = first if number == 0 else Episode(replace(request, seed=seed, log=_numbered(request.log, number)))
        controller = Controller(breakpoints, start_paused=True)
        control = FoxgloveControl(controller, host=request.live_host, allow_remote=allow_remote,
                                  control_files=control_files)
        episode.on_live.append(_server(episode, control, say, layout_folder))
        result = episode.run(on_tick=on_tick, controller=controller)
        if controller.restart is None:
            return result
        # a restart: the next episode keeps the breakpoints and serves on the same port (a viewer reconnects)
        breakpoints = tuple(parse_breakpoint(spec) for spec in controller.state().breakpoints)
        seed += 1 if controller.restart is SeedPolicy.NEXT else 0
        number += 1
        say(f"restart: episode {number + 1}, seed {seed}")


def _numbered(log: Path | None, number: int) -> Path | None:
    """Episode ``number``'s log after restarts: run.mcap, run-2.mcap, run-3.mcap, ... (as --interactive)."""
    return None if log is None or number == 0 else log.with_name(f"{log.stem}-{number + 1}{log.suffix}")


def _server(episode: Episode, control: FoxgloveControl, say: Say, layout_folder: Path | None) -> Callable[[str], None]:
    from bt_grasp.foxglove.tree_layout import write_live_layout

    request = episode.request  # the control layout of the tree that runs: its leaves' rows, by path
    layout = write_live_layout(request.tree, request.leaves, request.log, control=True, folder=layout_folder)

    def serve(url: str) -> None:
        assert episode.live is not None
        episode.live.serve_control(control)
        say(f"live control: in Foxglove, Open connection > Foxglove WebSocket > {url}, layout {layout}; the run is "
            "paused: set run.paused to false (or press Resume)")

    return serve
