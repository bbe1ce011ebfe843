"""The scene file (``scenes/*.yaml``): table, robot mount, camera, lights, objects, randomisation,
and (schema version 2) the task's goal, static fixtures and the calibration file shipped beside it.

Frames: the world frame has z up and its origin on the table top; the robot's ``base_link`` sits at
``robot.base_xyz_m``. Everything a robot would know from its installation drawing (the table, where the
robot is bolted, the camera's nominal mount) is here; the objects' drawn poses are the simulator's secret.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from bt_grasp.defaults import DEFAULT_PERCEPTION_LATENCY_S
from bt_grasp.errors import ConfigError
from bt_grasp.files.config import KeyPath, StrictModel, read_yaml, validate
from bt_grasp.scene.colors import COLOR_NAMES
from bt_grasp.scene.conveyor import Conveyor
from bt_grasp.scene.fixtures import CONTAINER_KINDS, Fixture
from bt_grasp.scene.goals import Goal, PickGoal, PlaceGoal, SortGoal, StackGoal
from bt_grasp.scene.objects import Choose, SceneObject

__all__ = ["COLOR_NAMES", "SCENE_VERSION", "Scene", "load_scene"]

log = logging.getLogger(__name__)

#: the scene file format this bt_grasp writes and reads (a file without ``version`` is version 1)
SCENE_VERSION = 2
#: keys that need ``version: 2``
_V2_KEYS = ("goal", "fixtures", "calibration", "object_gap_m", "choose", "packages", "perception_latency_s")
#: a top-down place is planned only this far (horizontally) from the robot base, m
TOP_DOWN_REACH_M = 0.80

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Vec3 = tuple[float, float, float]
Range = tuple[float, float]
PackageName = Annotated[str, Field(pattern=r"^[A-Za-z0-9_.\-]+$")]

#: physics steps one tree tick may take: 5 by default; 1e-9 s steps made one tick 10^7 steps (a run that never
#: ended, found by the pre-review attack)
MAX_STEPS_PER_TICK = 100


class Physics(StrictModel):
    timestep_s: Annotated[float, Field(ge=1e-4, le=0.004)] = 0.002  # dt <= 1/250 s keeps fingers out of boxes
    control_rate_hz: Annotated[float, Field(ge=1, le=1000)] = 100.0  # behaviour-tree ticks per second
    gravity_m_s2: Vec3 = (0.0, 0.0, -9.81)
    solver_position_iterations: Annotated[int, Field(ge=1, le=255)] = 20
    solver_velocity_iterations: Annotated[int, Field(ge=1, le=255)] = 4

    @model_validator(mode="after")
    def _steps_per_tick(self) -> Physics:
        steps = 1.0 / (self.control_rate_hz * self.timestep_s)
        if steps < 1 - 1e-9:
            raise ValueError(f"a tick ({1 / self.control_rate_hz:g} s) is shorter than one physics step "
                             f"({self.timestep_s:g} s)")
        if steps > MAX_STEPS_PER_TICK:
            raise ValueError(f"one tick would take {steps:.0f} physics steps (at most {MAX_STEPS_PER_TICK}): raise "
                             "control_rate_hz or timestep_s")
        return self


class Table(StrictModel):
    size_m: tuple[PositiveFloat, PositiveFloat, PositiveFloat] = (1.0, 1.4, 0.04)  # x, y, thickness
    center_xy_m: tuple[float, float] = (0.35, 0.0)
    color: str | tuple[float, float, float] = "wood"
    friction: NonNegFloat = 0.6


class RobotMount(StrictModel):
    base_xyz_m: Vec3 = (0.0, 0.0, 0.0)
    base_yaw_deg: float = 0.0
    home_q_rad: tuple[float, float, float, float, float, float] = (0.0, -1.9, 1.9, -1.57, -1.57, 0.0)
    gripper_force_n: PositiveFloat = 40.0
    finger_friction: NonNegFloat = 1.0


class EyeToHand(StrictModel):
    position_m: Vec3 = (1.05, 0.0, 0.75)
    look_at_m: Vec3 = (0.45, 0.0, 0.0)
    roll_deg: float = 0.0


class EyeInHand(StrictModel):
    parent_link: str = "tool0"
    xyz_m: Vec3 = (-0.07, 0.0, 0.01)  # optical centre relative to the parent link
    rpy_deg: Vec3 = (0.0, 12.0, 0.0)  # OpenCV optical axes (z forward) relative to the parent link


class DepthNoise(StrictModel):
    """A D435-like stereo depth error model: RMS error = z^2 * subpixel / (focal * baseline)."""

    enabled: bool = True
    baseline_m: PositiveFloat = 0.050
    focal_px: PositiveFloat = 383.0
    subpixel: NonNegFloat = 0.08
    quantum_m: NonNegFloat = 0.001
    min_range_m: NonNegFloat = 0.28
    max_range_m: PositiveFloat = 3.0
    edge_jump_m: PositiveFloat = 0.03  # depth discontinuity that invalidates neighbouring pixels
    edge_dropout: Annotated[float, Field(ge=0, le=1)] = 0.5  # probability an edge pixel reads invalid
    color_sigma: NonNegFloat = 2.0  # colour noise, standard deviation in 8-bit levels


class Camera(StrictModel):
    model: Literal["d435"] = "d435"
    width_px: Annotated[int, Field(gt=0, le=4096)] = 640
    height_px: Annotated[int, Field(gt=0, le=4096)] = 480
    vfov_deg: Annotated[float, Field(gt=1, lt=170)] = 42.0
    near_m: PositiveFloat = 0.05
    far_m: PositiveFloat = 10.0
    mount: Literal["eye-to-hand", "eye-in-hand"] = "eye-to-hand"
    eye_to_hand: EyeToHand = EyeToHand()
    eye_in_hand: EyeInHand = EyeInHand()
    noise: DepthNoise = DepthNoise()


class Light(StrictModel):
    kind: Literal["ambient", "directional", "point"]
    color: Vec3 = (1.0, 1.0, 1.0)
    direction: Vec3 = (0.0, 0.0, -1.0)
    position_m: Vec3 = (0.0, 0.0, 2.0)
    shadow: bool = False


class Workspace(StrictModel):
    """The region of the table where objects may be (world frame), for perception's region of interest."""

    x_m: Range = (0.25, 0.75)
    y_m: Range = (-0.35, 0.35)
    z_max_m: PositiveFloat = 0.30


class Scene(StrictModel):
    version: Annotated[int, Field(ge=1)] = 1
    name: str = "scene"
    physics: Physics = Physics()
    table: Table = Table()
    robot: RobotMount = RobotMount()
    camera: Camera = Camera()
    lights: tuple[Light, ...] = (
        Light(kind="ambient", color=(0.45, 0.45, 0.45)),
        Light(kind="directional", direction=(-0.3, 0.2, -1.0), color=(0.8, 0.8, 0.8)),
    )
    workspace: Workspace = Workspace()
    objects: tuple[SceneObject, ...] = ()
    #: (version 2) the smallest gap between drawn objects' footprints, m; 0 lets objects touch. Not given:
    #: the first format's rule (circumscribed circles 1 cm apart), which draws the same poses per seed
    object_gap_m: NonNegFloat | None = None
    #: (version 2) a seeded subset of the objects (see bt_grasp.scene.layout); None: every object, every run
    choose: Choose | None = None
    #: (version 2) static fixtures: trays, bins, markers, walls (see bt_grasp.scene.fixtures)
    fixtures: tuple[Fixture, ...] = ()
    #: (version 2) what a run on this scene is judged on; None: pick the object of the run's --color
    goal: Goal | None = None
    #: (version 2) the calibration file made by `bt-grasp calibrate` for this scene, relative to this file
    calibration: str | None = None
    #: (version 2) folders of the packages URDF objects name in ``package://NAME/...`` mesh paths, relative to
    #: this file (else found beside the URDF: bt_grasp.scene.urdf_object)
    packages: dict[PackageName, Annotated[str, Field(min_length=1)]] | None = None
    #: (version 2) how long after a frame's timestamp its detections reach the tree, s of simulated time; None:
    #: the package's default (``bt_grasp.defaults.DEFAULT_PERCEPTION_LATENCY_S``)
    perception_latency_s: Annotated[float, Field(ge=0, le=2.0)] | None = None

    @model_validator(mode="after")
    def _unique_names(self) -> Scene:
        names = [o.name for o in self.objects] + [f.name for f in self.fixtures]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"object and fixture names must be unique; repeated: {', '.join(dupes)}")
        return self

    @property
    def latency_s(self) -> float:
        """The perception latency a simulated run of this scene pays: its own, else the package's default."""
        return DEFAULT_PERCEPTION_LATENCY_S if self.perception_latency_s is None else float(self.perception_latency_s)

    def fixture(self, name: str) -> Fixture | None:
        return next((f for f in self.fixtures if f.name == name), None)

    def object_spec(self, name: str) -> SceneObject | None:
        return next((o for o in self.objects if o.name == name), None)

    def effective_goal(self, color: str | None = None) -> Goal:
        """The declared goal, or today's default: pick the object of the run's colour."""
        return self.goal if self.goal is not None else PickGoal(kind="pick", color=color or None)

    def T_world_base(self) -> np.ndarray:
        """Where the robot is bolted (installation data, known to the pipeline)."""
        yaw = np.deg2rad(self.robot.base_yaw_deg)
        T = np.eye(4)
        T[:3, :3] = [[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]]
        T[:3, 3] = self.robot.base_xyz_m
        return T


def load_scene(path: str | Path) -> Scene:
    """Load and validate a scene file; raises ConfigError naming the file, line and key.

    A file without ``version`` is version 1 (the first format) and loads as before; a version-1 file that
    uses a version-2 key gets one sentence saying to add ``version: 2``.
    """
    data, lines = read_yaml(path)
    if isinstance(data, dict):
        _check_version(data, path, lines)
    scene = validate(Scene, data, path, lines)
    check_references(scene, path, lines)
    check_choose(scene, path, lines)
    feeds = [(i, f.feed.objects) for i, f in enumerate(scene.fixtures) if isinstance(f, Conveyor) and f.feed]
    if any(o.is_mesh for o in scene.objects) or any(o.is_mesh for _, objects in feeds for o in objects):
        from bt_grasp.scene.meshes import attach_geometry  # deferred: trimesh is imported only for scenes with meshes

        table = max(scene.table.size_m[0], scene.table.size_m[1])
        packages = _package_folders(scene, path, lines)
        attach_geometry(scene.objects, table, path, lines, packages)
        for i, objects in feeds:  # a conveyor's feed: the templates of the objects that enter during the run
            attach_geometry(objects, table, path, lines, packages, where=("fixtures", i, "feed", "objects"))
        _note_objects_beyond_the_gripper(scene)
    return scene


def _note_objects_beyond_the_gripper(scene: Scene) -> None:
    from bt_grasp.scene.graspability import object_warning  # deferred: only scenes with mesh objects need it
    from bt_grasp.scene.notices import notice  # deferred: as above

    for obj in scene.objects:
        if obj.is_mesh:
            sentence = object_warning(obj.name, obj.geometry, obj.mass_or_default_kg, obj.friction,
                                      scene.robot.gripper_force_n, scene.robot.finger_friction)
            if sentence is not None:
                notice(log, sentence)


def _package_folders(scene: Scene, path: str | Path, lines: dict[KeyPath, int]) -> dict[str, Path]:
    """The scene's ``packages:``, each a folder relative to the scene file that must exist."""
    folders: dict[str, Path] = {}
    for name, folder in (scene.packages or {}).items():
        resolved = Path(path).parent / folder
        if not resolved.is_dir():
            raise ConfigError(path, f"package '{name}' is mapped to '{folder}', which is not a folder",
                              where=lines.get(("packages", name), lines.get(("packages",))))
        folders[name] = resolved
    return folders


def _check_version(data: dict[str, object], path: str | Path, lines: dict[KeyPath, int]) -> None:
    version = data.get("version", 1)
    if not isinstance(version, int) or isinstance(version, bool):
        return  # the model reports the type error with its line
    if version > SCENE_VERSION:
        raise ConfigError(path, f"scene format version {version} is newer than this bt_grasp reads "
                          f"({SCENE_VERSION}); update bt_grasp or write a version-{SCENE_VERSION} scene",
                          where=lines.get(("version",)))
    if version < SCENE_VERSION:
        for key in _V2_KEYS:
            if key in data:
                raise ConfigError(path, f"'{key}' needs scene format version {SCENE_VERSION}: add "
                                  f"'version: {SCENE_VERSION}' at the top of the file", where=lines.get((key,)))


def check_choose(scene: Scene, path: str | Path, lines: dict[KeyPath, int] | None = None) -> None:
    """``choose`` names objects of the scene, once each, and no more of them than there are; a goal names no
    object that a run may leave out."""
    choose = scene.choose
    if choose is None:
        return
    lines = lines or {}
    names = [o.name for o in scene.objects]
    among = list(choose.among) if choose.among is not None else names
    where = lines.get(("choose", "among"), lines.get(("choose",)))
    for i, name in enumerate(among):
        line = lines.get(("choose", "among", i), where)
        if name not in names:
            raise ConfigError(path, f"choose names object '{name}', which is not in the scene (objects: "
                              f"{', '.join(names) or 'none'})", where=line)
        if among.count(name) > 1:
            raise ConfigError(path, f"choose names object '{name}' twice", where=line)
    low, high = choose.count_range
    if high > len(among):
        raise ConfigError(path, f"choose draws up to {high} objects among {len(among)}",
                          where=lines.get(("choose", "count"), where))
    goal = scene.goal
    named = {getattr(goal, key, None) for key in ("object", "on")} if goal is not None else set()
    left_out = sorted(n for n in named if isinstance(n, str) and n in among and low < len(among))
    if left_out:
        raise ConfigError(path, f"the goal names object '{left_out[0]}', which choose may leave out of a run",
                          where=lines.get(("goal",)))


def check_references(scene: Scene, path: str | Path, lines: dict[KeyPath, int] | None = None) -> None:
    """Names a goal uses exist in the scene, containers are trays or bins, place targets can be reached."""
    lines = lines or {}
    goal = scene.goal
    if goal is None:
        return
    objects = [o.name for o in scene.objects]
    fixtures = [f.name for f in scene.fixtures]

    def fail(key: KeyPath, problem: str) -> None:
        line = next((lines[key[:i]] for i in range(len(key), 0, -1) if key[:i] in lines), None)
        raise ConfigError(path, problem, where=line)

    def need_object(name: str | None, key: KeyPath) -> None:
        if name is not None and name not in objects:
            known = ", ".join(objects) or "none"
            fail(key, f"goal names object '{name}', which is not in the scene (objects: {known})")

    def need_container(name: str | None, key: KeyPath) -> None:
        if name is None:
            return
        fixture = scene.fixture(name)
        if fixture is None:
            known = ", ".join(fixtures) or "none"
            fail(key, f"goal names fixture '{name}', which is not in the scene (fixtures: {known})")
        elif fixture.kind not in CONTAINER_KINDS:
            fail(key, f"goal puts objects into '{name}', a {fixture.kind}; only a tray or a bin holds objects")

    if isinstance(goal, PickGoal):
        need_object(goal.object, ("goal", "object"))
    elif isinstance(goal, PlaceGoal):
        need_object(goal.object, ("goal", "object"))
        if goal.at is not None and scene.fixture(goal.at) is None:
            fail(("goal", "at"), f"goal names fixture '{goal.at}', which is not in the scene "
                 f"(fixtures: {', '.join(fixtures) or 'none'})")
        fixture = scene.fixture(goal.at) if goal.at is not None else None
        xy = goal.at_xy_m if goal.at_xy_m is not None else (fixture.center_xy_m if fixture else (0.0, 0.0))
        problem = place_xy_problem(scene, xy)
        if problem:
            fail(("goal", "at_xy_m" if goal.at_xy_m is not None else "at"), f"the place target {problem}")
    elif isinstance(goal, StackGoal):
        need_object(goal.object, ("goal", "object"))
        need_object(goal.on, ("goal", "on"))
        if goal.object == goal.on:
            fail(("goal", "on"), "an object cannot be stacked on itself")
    elif isinstance(goal, SortGoal):
        for i, rule in enumerate(goal.rules):
            need_container(rule.into, ("goal", "rules", i, "into"))
    else:
        need_container(goal.into, ("goal", "into"))
    for i, f in enumerate(scene.fixtures):
        problem = place_xy_problem(scene, f.center_xy_m, reach=False)
        if problem:
            fail(("fixtures", i, "center_xy_m"), f"fixture '{f.name}' {problem}")


def place_xy_problem(scene: Scene, xy: tuple[float, float], reach: bool = True) -> str | None:
    """Why a world (x, y) cannot be a top-down place target (off the table, out of reach), or None."""
    table = scene.table
    dx, dy = xy[0] - table.center_xy_m[0], xy[1] - table.center_xy_m[1]
    if abs(dx) > table.size_m[0] / 2 or abs(dy) > table.size_m[1] / 2:
        return f"({xy[0]:.3f}, {xy[1]:.3f}) m is off the table"
    base = scene.robot.base_xyz_m
    distance = float(np.hypot(xy[0] - base[0], xy[1] - base[1]))
    if reach and not 0.20 <= distance <= TOP_DOWN_REACH_M:
        return (f"({xy[0]:.3f}, {xy[1]:.3f}) m is out of reach: {distance:.2f} m from the robot base "
                f"(a top-down place needs 0.20 to {TOP_DOWN_REACH_M:.2f} m)")
    return None
