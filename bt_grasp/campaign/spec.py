"""Campaign files: trees x scenes x seeds x fault plans x blackboard parameters, loaded strictly.

A campaign file is YAML validated like every other file a user writes: unknown keys, missing files and
files that do not load (a tree with an unknown node, a scene with a typo, a bad fault plan) are refused
before any episode runs, with one sentence naming the campaign file, the line and the problem.

Paths in a campaign file are relative to the campaign file's folder.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from pydantic import Field, field_validator, model_validator

from bt_grasp.episode.request import BlackboardValue, EpisodeRequest, run_blackboard
from bt_grasp.errors import ConfigError, InputError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.files.config import KeyPath, StrictModel, format_key_path, read_yaml, validate
from bt_grasp.files.output_files import write_output_file
from bt_grasp.scene.goals import Goal

NO_FAULTS = "none"
#: how a campaign file gives a calibration of its own (the missing-calibration sentence's way out)
CAMPAIGN_CALIBRATION = ("give the campaign file a 'calibration' key (every scene) or the scene's entry one "
                        "({file: ..., calibration: ...})")
MAX_EPISODES = 1_000_000
#: seeds are 64-bit signed integers everywhere a result is written (results rows, Parquet)
MAX_SEED = 2**63 - 1
#: a campaign's name names its results file inside --out (and out/NAME by default): one plain file-name part,
#: never hidden and never ``.`` or ``..`` (a name ``..`` put the results beside out/, not in it)
NAME_PATTERN = r"^[A-Za-z0-9_-][A-Za-z0-9_.-]{0,99}$"


class SeedRange(StrictModel):
    first: int = Field(0, ge=0, le=MAX_SEED)  # the first seed
    count: int = Field(..., ge=1, le=MAX_EPISODES)  # how many consecutive seeds

    @model_validator(mode="after")
    def _last_fits(self) -> SeedRange:
        if self.first + self.count - 1 > MAX_SEED:
            raise ValueError(f"the last seed {self.first + self.count - 1} is over {MAX_SEED} (2**63 - 1)")
        return self


class SceneEntry(StrictModel):
    file: str  # scene YAML, relative to the campaign file
    calibration: str | None = None  # calibration YAML for this scene (else the campaign's, else the scene's own)
    name: str | None = None  # label in results and reports (default: the file's stem)
    goal: Goal | None = None  # what the judge checks (default: the scene's declared goal, else a pick)


class FaultPlanEntry(StrictModel):
    name: str  # label in results and reports
    file: str | None = None  # fault plan YAML, relative to the campaign file
    inject: tuple[str, ...] = ()  # `--inject` strings, e.g. "frame_drop@Perceive#1"

    @model_validator(mode="after")
    def _something(self) -> FaultPlanEntry:
        if self.file is None and not self.inject:
            raise ValueError("a fault plan needs a file or inject strings (use 'none' for no faults)")
        return self


class CampaignFile(StrictModel):
    name: str = Field(..., min_length=1)  # names the results file (NAME_PATTERN)
    description: str = ""
    trees: tuple[str, ...] = Field(..., min_length=1)  # tree files (XML or YAML)
    scenes: tuple[str | SceneEntry, ...] = Field(..., min_length=1)
    seeds: SeedRange | tuple[int, ...]  # {first, count} or an explicit list
    fault_plans: tuple[str | FaultPlanEntry, ...] = (NO_FAULTS,)  # "none", a file, or {name, file, inject}
    #: each a parameter set: entries over `bt-grasp run`'s own (``run_blackboard``: lift_height 0.15, the colour of
    #: the goal), as `--set KEY=VALUE` puts them; default: one empty set, i.e. exactly `bt-grasp run`'s episode
    blackboard: tuple[dict[str, str | int | float | bool], ...] = ({},)
    calibration: str | None = None  # default calibration for every scene
    max_ticks: int = Field(12000, ge=1)  # per episode (100 Hz ticks of simulated time)

    @field_validator("name")
    @classmethod
    def _name(cls, value: str) -> str:
        if not re.fullmatch(NAME_PATTERN, value):
            raise ValueError("a campaign's name names its results file: letters, digits, '_', '.' and '-', not "
                             "starting with '.', at most 100 characters")
        return value

    @field_validator("seeds")
    @classmethod
    def _seeds(cls, value: SeedRange | tuple[int, ...]) -> SeedRange | tuple[int, ...]:
        if isinstance(value, tuple):
            if not value:
                raise ValueError("the seed list is empty")
            if len(set(value)) != len(value):
                raise ValueError("the seed list repeats a seed")
            if min(value) < 0 or max(value) > MAX_SEED:
                raise ValueError(f"seeds must be from 0 to {MAX_SEED} (2**63 - 1)")
        return value


@dataclass(frozen=True)
class FaultPlanRef:
    """One fault-plan axis value: a label plus what to load (nothing for 'none')."""

    name: str
    file: Path | None = None
    inject: tuple[str, ...] = ()

    @property
    def is_none(self) -> bool:
        return self.file is None and not self.inject


@dataclass(frozen=True)
class SceneRef:
    name: str
    file: Path
    calibration: Path | None
    goal: Goal | None = None


@dataclass(frozen=True)
class PlannedEpisode:
    """One episode a campaign plans: the request it runs (every input, as ``bt-grasp run`` takes them) and the
    campaign's labels for it; ``key`` identifies it across runs (resume) and machines."""

    campaign: str
    index: int
    tree: str  # as written in the campaign file
    scene: str  # the scene's label
    fault_plan: str  # the fault plan's label ("none")
    params: tuple[tuple[str, str | int | float | bool], ...]
    inputs_digest: str  # content hash of every input file of this episode
    request: EpisodeRequest

    @property
    def seed(self) -> int:
        return self.request.seed

    @property
    def max_ticks(self) -> int:
        return self.request.max_ticks

    @property
    def blackboard(self) -> dict[str, str | int | float | bool]:
        return dict(self.params)

    @property
    def key(self) -> str:
        """Stable id: the same inputs (file contents included) give the same key."""
        goal = self.request.goal
        text = json.dumps(
            [
                self.tree,
                self.scene,
                self.seed,
                self.fault_plan,
                self.params,
                self.max_ticks,
                self.inputs_digest,
                goal.model_dump(mode="json") if goal is not None else None,
            ],
            sort_keys=True,
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def label(self) -> str:
        return f"{Path(self.tree).stem}/{self.scene}/seed{self.seed}/{self.fault_plan}"


@dataclass(frozen=True)
class Campaign:
    name: str
    source: Path
    description: str
    trees: tuple[str, ...]
    scenes: tuple[SceneRef, ...]
    seeds: tuple[int, ...]
    fault_plans: tuple[FaultPlanRef, ...]
    blackboard: tuple[dict[str, BlackboardValue], ...]
    max_ticks: int
    base: Path
    digests: dict[Path, str] = field(default_factory=dict, compare=False)
    leaves: tuple[str, ...] = ()  # users' own nodes (``eval run --leaves``), loaded by every episode

    def episodes(self) -> list[PlannedEpisode]:
        return list(self._iter())

    def request(self, tree: str, scene: SceneRef, plan: FaultPlanRef, params: Mapping[str, BlackboardValue], seed: int
                ) -> EpisodeRequest:
        """The one mapping from a campaign's row (tree x scene x fault plan x parameters x seed) to the request
        ``bt-grasp run`` would make of the same inputs."""
        return EpisodeRequest(
            tree=self.base / tree,
            scene=scene.file,
            seed=seed,
            goal=scene.goal,
            calibration=scene.calibration,
            faults=plan.file,
            inject=plan.inject,
            blackboard=run_blackboard(params),  # run's rule: the same settings, the same blackboard
            max_ticks=self.max_ticks,
            leaves=self.leaves,
        )

    def _iter(self) -> Iterator[PlannedEpisode]:
        grid = itertools.product(self.trees, self.scenes, self.fault_plans, range(len(self.blackboard)), self.seeds)
        for index, (tree, scene, plan, params_i, seed) in enumerate(grid):
            tree_file = self.base / tree
            files = [tree_file, scene.file, scene.calibration, plan.file]
            digest = hashlib.sha256(
                "|".join(self.digests.get(f, "") if f is not None else "-" for f in files).encode()
            ).hexdigest()[:16]
            yield PlannedEpisode(
                campaign=self.name,
                index=index,
                tree=tree,
                scene=scene.name,
                fault_plan=plan.name,
                params=tuple(sorted(self.blackboard[params_i].items())),
                inputs_digest=digest,
                request=self.request(tree, scene, plan, self.blackboard[params_i], seed),
            )


def _digest(path: Path) -> str:
    return hashlib.sha256(read_user_file(path, error=ConfigError)).hexdigest()  # bounded: no device, no giant


def load_campaign(path: str | Path, *, check_inputs: bool = True, leaves: tuple[str, ...] = ()) -> Campaign:
    """Read, validate and resolve a campaign file; with ``check_inputs`` every tree, scene, calibration and
    fault plan it names is loaded too, so a bad input stops the campaign before its first episode. ``leaves``:
    plugin files or modules with users' own nodes (docs/own-leaves.md), for the checks and every episode."""
    path = Path(path)
    data, lines = read_yaml(path)
    parsed = validate(CampaignFile, data, path, lines)
    base = path.parent
    digests: dict[Path, str] = {}

    def existing(rel: str, key: KeyPath) -> Path:
        full = base / rel
        if not full.is_file():
            raise ConfigError(
                path,
                f"{_where(key)}: no such file '{rel}' (paths are relative to the campaign file)",
                _line(lines, key),
            )
        digests[full] = _digest(full)
        return full

    default_cal = existing(parsed.calibration, ("calibration",)) if parsed.calibration else None
    for i, tree in enumerate(parsed.trees):
        existing(tree, ("trees", i))
    scenes: list[SceneRef] = []
    for i, entry in enumerate(parsed.scenes):
        item = entry if isinstance(entry, SceneEntry) else SceneEntry(file=entry)
        key: KeyPath = ("scenes", i) if isinstance(entry, str) else ("scenes", i, "file")
        scene_file = existing(item.file, key)
        override = existing(item.calibration, ("scenes", i, "calibration")) if item.calibration else default_cal
        calibration = _scene_calibration(path, lines, ("scenes", i), scene_file, override)
        if calibration is not None:
            digests[calibration] = _digest(calibration)
        scenes.append(SceneRef(item.name or Path(item.file).stem, scene_file, calibration, item.goal))
    plans: list[FaultPlanRef] = []
    for i, plan in enumerate(parsed.fault_plans):
        if isinstance(plan, str):
            plans.append(
                FaultPlanRef(NO_FAULTS)
                if plan == NO_FAULTS
                else FaultPlanRef(Path(plan).stem, existing(plan, ("fault_plans", i)))
            )
        else:
            file = existing(plan.file, ("fault_plans", i, "file")) if plan.file else None
            plans.append(FaultPlanRef(plan.name, file, plan.inject))
    _unique(path, lines, "scenes", [s.name for s in scenes])
    _unique(path, lines, "fault_plans", [p.name for p in plans])
    _unique(path, lines, "trees", list(parsed.trees))
    seed_count = parsed.seeds.count if isinstance(parsed.seeds, SeedRange) else len(parsed.seeds)
    total = len(parsed.trees) * len(scenes) * len(plans) * len(parsed.blackboard) * seed_count
    if total > MAX_EPISODES:  # counted before any list of them is made
        raise ConfigError(path, f"{total} episodes is more than the limit of {MAX_EPISODES}; split the campaign", 1)
    seeds = (
        tuple(range(parsed.seeds.first, parsed.seeds.first + parsed.seeds.count))
        if isinstance(parsed.seeds, SeedRange)
        else parsed.seeds
    )
    campaign = Campaign(
        name=parsed.name,
        source=path,
        description=parsed.description,
        trees=parsed.trees,
        scenes=tuple(scenes),
        seeds=seeds,
        fault_plans=tuple(plans),
        blackboard=tuple(dict(b) for b in parsed.blackboard),
        max_ticks=parsed.max_ticks,
        base=base,
        digests=digests,
        leaves=tuple(leaves),
    )
    if check_inputs:
        _check_inputs(campaign, lines)
    return campaign


def _check_inputs(campaign: Campaign, lines: dict[KeyPath, int]) -> None:
    """Load every tree, scene, calibration and fault plan once (no simulator): errors name the campaign too."""
    from bt_grasp.behaviours import robot_registry  # deferred: start-up time (the leaf library: checks only)
    from bt_grasp.faults.plan import load_fault_plan  # deferred: start-up time (checks only)
    from bt_grasp.tree.loader import load_tree  # deferred: start-up time (the tree package: checks only)

    src = campaign.source

    def checked(key: KeyPath, what: str, load: Callable[[], object]) -> object:
        try:
            return load()
        except InputError as exc:
            raise ConfigError(src, f"{_where(key)} ({what}) does not load: {exc.message}", _line(lines, key)) from None

    def tree_loads(tree: str) -> object:
        return load_tree(campaign.base / tree, robot_registry(campaign.leaves))

    for i, tree in enumerate(campaign.trees):
        checked(("trees", i), "tree", partial(tree_loads, tree))
    for i, plan in enumerate(campaign.fault_plans):
        if not plan.is_none:
            checked(("fault_plans", i), "fault plan", partial(load_fault_plan, plan.file, plan.inject))
    _check_combinations(campaign, lines)


def _check_combinations(campaign: Campaign, lines: dict[KeyPath, int]) -> None:
    """Every tree x scene x fault plan x parameter set passes the episode API's own input checks (goal names,
    tree leaves against the scene, fault plans against the tree), once, before the first episode runs."""
    from bt_grasp.episode import load_inputs  # deferred: start-up time (the episode module and its simulator)

    seed = campaign.seeds[0]
    for (ti, tree), (si, scene), (fi, plan), (bi, params) in itertools.product(
        enumerate(campaign.trees),
        enumerate(campaign.scenes),
        enumerate(campaign.fault_plans),
        enumerate(campaign.blackboard),
    ):
        try:
            load_inputs(campaign.request(tree, scene, plan, params, seed))
        except InputError as exc:
            where = f"trees[{ti}] on scenes[{si}] with fault_plans[{fi}] and blackboard[{bi}]"
            raise ConfigError(
                campaign.source, f"{where} cannot run: {exc.message}", _line(lines, ("scenes", si))
            ) from None


def _scene_calibration(
    path: Path, lines: dict[KeyPath, int], key: KeyPath, scene_file: Path, override: Path | None
) -> Path | None:
    """The scene loads, and the calibration its episodes use (the campaign's, else the scene's own) fits it."""
    # deferred: start-up time (the perception package; a resumed campaign with check_inputs=False skips it)
    from bt_grasp.perception.calibration_file import calibration_for_scene
    from bt_grasp.scene.format import load_scene  # deferred: start-up time (checks only)

    try:
        config = load_scene(scene_file)
        return calibration_for_scene(config, scene_file, override, give_one=CAMPAIGN_CALIBRATION)[0]
    except InputError as exc:
        raise ConfigError(path, f"{_where(key)} (scene) does not load: {exc.message}", _line(lines, key)) from None


def _unique(path: Path, lines: dict[KeyPath, int], key: str, names: list[str]) -> None:
    seen: set[str] = set()
    for i, name in enumerate(names):
        if name in seen:
            raise ConfigError(
                path, f"{key}[{i}]: the label '{name}' is used twice; give one a 'name'", _line(lines, (key, i))
            )
        seen.add(name)


def _where(key: KeyPath) -> str:
    return format_key_path(key)


def _line(lines: dict[KeyPath, int], key: KeyPath) -> int | None:
    while key:
        if key in lines:
            return lines[key]
        key = key[:-1]
    return None


def check_options_inputs(trees: list[Path], scenes: list[Path], calibration: Path | None, max_ticks: int,
                         leaves: tuple[str, ...] = ()) -> None:
    """`eval run --tree T --scene S [--calibration C]`'s inputs checked as ``bt-grasp run`` checks them, every
    tree on every scene, before anything is written: a refusal names the user's own files and flags (the campaign
    file these options stand for is not written yet, so it is never named, nor left behind)."""
    from bt_grasp.episode import load_inputs  # deferred: start-up time (the episode module and its simulator)

    given = [calibration] if calibration is not None else []
    for flag, paths in (("--tree", trees), ("--scene", scenes), ("--calibration", given)):
        for path in paths:
            if not path.is_file():
                raise InputError(flag, f"no such file '{path}'")
    for tree, scene in itertools.product(trees, scenes):
        load_inputs(EpisodeRequest(tree=tree, scene=scene, calibration=calibration, blackboard=run_blackboard(),
                                   max_ticks=max_ticks, leaves=leaves))


def options_campaign_path(trees: list[Path], scenes: list[Path], name: str | None, out: Path | None) -> Path:
    """Where `eval run --tree T --scene S` writes the campaign file it stands for (``OUT/NAME.campaign.yaml``;
    ``OUT`` defaults to ``out/NAME``, ``NAME`` to the stems of the trees and scenes)."""
    if name is None:
        name = "-".join(dict.fromkeys(p.stem for p in [*trees, *scenes]))
    if not re.fullmatch(NAME_PATTERN, name):
        raise InputError("--name", f"'{name[:120]}' may hold only letters, digits, '_', '.' and '-', not start with "
                                   "'.', and have at most 100 characters (it names the results file)")
    folder = Path("out") / name if out is None else out
    return folder / f"{name}.campaign.yaml"


def write_options_campaign(
    trees: list[Path], scenes: list[Path], seeds: int, first_seed: int, name: str | None, out: Path | None,
    *, max_ticks: int | None = None, calibration: Path | None = None,
) -> Path:
    """The campaign file `eval run --tree T --scene S --seeds N [--calibration C]` stands for, written into the
    output folder (``NAME.campaign.yaml``: the run is resumable and its inputs are on record). Paths in it are
    absolute. Check the inputs first (:func:`check_options_inputs`)."""
    import yaml

    for flag, paths in (("--tree", trees), ("--scene", scenes)):
        for path in paths:
            if not path.is_file():
                raise InputError(flag, f"no such file '{path}'")
    target = options_campaign_path(trees, scenes, name, out)
    data: dict[str, object] = {
        "name": target.name.removesuffix(".campaign.yaml"),
        "description": "written by `bt-grasp eval run --tree ... --scene ...`",
        "trees": [str(p.resolve()) for p in trees],
        "scenes": [str(p.resolve()) for p in scenes],
        "seeds": {"first": first_seed, "count": seeds},
    }
    if calibration is not None:
        data["calibration"] = str(calibration.resolve())
    if max_ticks is not None:
        data["max_ticks"] = max_ticks
    return write_output_file(target, yaml.safe_dump(data, sort_keys=False), "--out")
