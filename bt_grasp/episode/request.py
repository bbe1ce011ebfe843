"""What one episode is asked to do: every input as a path or a value, nothing built yet."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from bt_grasp.defaults import DEFAULT_LIFT_HEIGHT_M
from bt_grasp.defaults import DEFAULT_MAX_TICKS as DEFAULT_MAX_TICKS
from bt_grasp.errors import InputError
from bt_grasp.scene.goals import Goal

#: what a user may put on the blackboard before the first tick (``--set KEY=VALUE``)
BlackboardValue = str | int | float | bool


@dataclass(frozen=True)
class EpisodeRequest:
    """One episode: a tree on a scene with a seed, judged against ``goal``.

    ``goal``: what the judge checks; None: the scene's declared goal, else a pick of the blackboard's
    ``color`` lifted by its ``lift_height`` (:func:`bt_grasp.scene.run_goal.goal_for_run`).
    ``calibration``: a calibration file to load before the first tick (``LoadCalibration`` may load one
    too); ``log``: write the run to this MCAP file; ``faults``/``inject``: a fault plan file and/or
    one-line faults; ``blackboard``: entries set on the main tree's blackboard before the first tick;
    ``argv``: the command line, recorded in the log's metadata. ``image_hz``, ``live_port``/``live_host``
    and ``realtime`` only observe the run (see ``bt_grasp.episode.observers`` and ``bt_grasp.foxglove.live``).
    """

    tree: Path
    scene: Path
    seed: int = 0
    goal: Goal | None = None
    calibration: Path | None = None
    log: Path | None = None
    max_ticks: int = DEFAULT_MAX_TICKS
    faults: Path | None = None
    inject: tuple[str, ...] = ()
    blackboard: Mapping[str, BlackboardValue] = field(default_factory=dict)
    argv: tuple[str, ...] = ()
    #: observers (they never change the run): extra camera frames per simulated second in the log (0: only
    #: at a leaf's failure and at the end), a live Foxglove WebSocket view on this port (None: none; 0: any
    #: free port) and host, and wall-clock pacing (simulated seconds per wall second; None: as fast as it goes)
    image_hz: float = 0.0
    #: compute the run fingerprint while the run goes (``EpisodeResult.fingerprint``), with or without a log
    fingerprint: bool = False
    live_port: int | None = None
    live_host: str = "127.0.0.1"
    realtime: float | None = None
    #: users' own nodes: ``--leaves`` plugin files or modules, loaded after the installed entry points
    leaves: tuple[str, ...] = ()
    #: the perception latency to pay, s (``bt_grasp.behaviours.cell.Cell.perception_latency_s``); None: the
    #: scene's (``Scene.latency_s``). ``replay --resim`` gives a log's recorded value (0 for a log made before
    #: latency was paid)
    perception_latency_s: float | None = None
    #: the log's time origin fixed (ns since 1970, from ``SOURCE_DATE_EPOCH``): the log then holds no wall-clock
    #: reading, so the same request writes the same bytes (``bt_grasp.recording.reproducible``); None: now
    log_epoch_ns: int | None = None
    #: more goals the judge checks at the end besides ``goal`` (``EpisodeResult.also_judged``; they decide
    #: nothing): a benchmark's figures under another definition of the same task, from the same run
    also_judge: tuple[Goal, ...] = ()


def run_blackboard(entries: Mapping[str, BlackboardValue] | None = None, *, color: str | None = None,
                   lift_height: float = DEFAULT_LIFT_HEIGHT_M) -> dict[str, BlackboardValue]:
    """The one rule for what a run puts on the main blackboard before its first tick, whoever asks for it
    (``bt-grasp run``, a campaign's episode, ``bench tasks``): ``lift_height`` (``--lift-height``, default 0.15 m),
    ``color`` only when one is given (``--color``; else the goal's: the scene's declared goal, else a pick of
    the scene's default colour, :func:`bt_grasp.scene.run_goal.default_color`), then ``entries`` over them
    (``--set KEY=VALUE``; a campaign's ``blackboard`` row). The same settings give the same blackboard, so the
    same episode."""
    out: dict[str, BlackboardValue] = {"lift_height": lift_height}
    if color is not None:
        out["color"] = color
    out.update(entries or {})
    return out


def parse_assignments(items: Sequence[str], source: str = "--set") -> dict[str, BlackboardValue]:
    """KEY=VALUE pairs; values are parsed as YAML scalars (numbers, true/false) or kept as text."""
    from bt_grasp.files.bounded_yaml import scalar_or_text

    out: dict[str, BlackboardValue] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InputError(source, f"expected KEY=VALUE, got '{item}'")
        out[key] = scalar_or_text(value)
    return out


def pick_request(tree: Path, scene: Path, seed: int, *, calibration: Path | None, log: Path | None = None,
                 argv: tuple[str, ...] = ()) -> EpisodeRequest:
    """The default pick (`bt-grasp demo`, `bt-grasp bench pick`): the red object lifted the default height,
    judged as a pick goal, with the tree's ``color`` and ``lift_height`` entries set to match."""
    from bt_grasp.defaults import DEFAULT_LIFT_HEIGHT_M
    from bt_grasp.scene.run_goal import goal_from_options

    return EpisodeRequest(tree=tree, scene=scene, seed=seed, goal=goal_from_options("pick", "red"),
                          calibration=calibration, log=log, argv=argv,
                          blackboard={"color": "red", "lift_height": DEFAULT_LIFT_HEIGHT_M})
