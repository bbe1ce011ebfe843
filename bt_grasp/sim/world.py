"""The simulated work cell built from a scene file and a seed."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import sapien

from bt_grasp.clock import ManualClock
from bt_grasp.interfaces import Mount
from bt_grasp.scene.format import COLOR_NAMES, Scene, load_scene
from bt_grasp.scene.layout import draw_layout
from bt_grasp.seeds import RunSeeds, Stream
from bt_grasp.sim.camera import SimCamera
from bt_grasp.sim.conveyor import BeltEncoder, BeltFeed, belts_for, on_supports
from bt_grasp.sim.device import create_scene
from bt_grasp.sim.fixtures import build_fixture
from bt_grasp.sim.objects import PlacedObject, build_object, draw_poses
from bt_grasp.sim.robot import SimRobot

log = logging.getLogger(__name__)

#: settling ends when every object moves slower than this (centre speed, m/s) ...
SETTLE_SPEED_M_S = 0.002
#: ... and turns slower than this (rad/s) ...
SETTLE_SPIN_RAD_S = 0.02
#: ... for this many control periods in a row, or after SETTLE_MAX_S of simulated time
SETTLE_STILL_TICKS = 5
SETTLE_MAX_S = 2.0
#: while settling (and only then) the objects' motion is damped this much (PhysX's per-second damping
#: coefficients; the defaults, restored for the run, are 0.05 angular and 0 linear): a lying can or bottle that
#: lands on the edge of a facet of its convex hull rolls on at 6-10 cm/s with the defaults (PhysX has no rolling
#: resistance), so runs began with it rolling off the table (learned seeds 128, 146, 169)
SETTLE_ANGULAR_DAMPING = 20.0
SETTLE_LINEAR_DAMPING = 5.0


class World:
    """SAPIEN scene + robot + camera + objects. Time passes only through :meth:`step`.

    Built afresh for every episode (never reset: ``bt_grasp.sim.render_keeper`` says why). Implements
    :class:`bt_grasp.interfaces.Stepper`. ``world.robot`` and ``world.camera`` implement the
    robot and camera interfaces; true object poses are reachable only through
    :class:`bt_grasp.sim.oracle.GroundTruthOracle`.
    """

    def __init__(
        self, scene_config: Scene, seed: int, *, camera_mount: str | None = None, source: str | Path = "scene",
        robot_urdf: Path | None = None,
    ) -> None:
        """``robot_urdf``: the robot with another gripper (``bt_grasp.cell.grippers``); None: bt_grasp's."""
        self.config = scene_config
        self._seed_streams(seed)
        self.clock = ManualClock()
        self.camera_mount = Mount(camera_mount or scene_config.camera.mount)
        physics = scene_config.physics
        self.scene = create_scene()
        self.scene.set_timestep(physics.timestep_s)
        sapien.physx.get_scene_config()  # touch: scene config applies to scenes created after a change
        self._build_table()
        self.robot = SimRobot(self.scene, scene_config.robot, scene_config.T_world_base(), robot_urdf)
        self.fixtures = {f.name: build_fixture(self.scene, f) for f in scene_config.fixtures}
        self.belts = belts_for(self.scene, scene_config.fixtures)
        layout = draw_layout(scene_config, self._object_rng)  # the seeded subset and rest poses (none: no draw)
        if layout.objects != scene_config.objects:  # the run's scene holds the objects drawn for it
            self.config = scene_config = scene_config.model_copy(update={"objects": layout.objects})
        self.placed: list[PlacedObject] = on_supports(draw_poses(
            layout.objects, self._object_rng, 0.0, str(source), scene_config.object_gap_m, layout.rest
        ), scene_config.fixtures)
        self.objects = {p.spec.name: build_object(self.scene, p) for p in self.placed}
        #: the conveyors' encoders by fixture name (``bt_grasp.interfaces.Encoder``), for the cell's devices
        self.encoders = {b.spec.name: BeltEncoder(b) for b in self.belts if b.spec.encoder is not None}
        feed_rng = self.seeds.generator(Stream.BELT_FEED)  # one stream for every feed, in fixture order
        self.feeds = [BeltFeed(b, feed_rng) for b in self.belts if b.spec.feed is not None]
        #: objects that entered during the run (a conveyor's feed): name -> T_world_object as set down
        self.entered: dict[str, np.ndarray] = {}
        self._build_lights()
        mount = self.camera_mount
        parent = None
        if mount == Mount.EYE_IN_HAND:
            parent = self.robot.links[scene_config.camera.eye_in_hand.parent_link]
        self.camera = SimCamera(self.scene, scene_config.camera, mount, self.camera_rng, self.clock.now_ns, parent)
        self._physics_steps = 0
        #: physics steps spent letting mesh objects settle before the run's first tick (0 without mesh objects)
        self.settle_steps = self.settle() if any(p.spec.is_mesh for p in self.placed) else 0
        log.debug("world built: seed %d, %d objects", self.seed, len(self.objects))

    def _seed_streams(self, seed: int) -> None:
        """The world's three streams of the run's seed (``bt_grasp.seeds``): separate, so that drawing more
        camera noise never moves an object and a fault plan never changes the scene it acts on."""
        self.seed = int(seed)
        self.seeds = RunSeeds(self.seed)
        self._object_rng = self.seeds.generator(Stream.OBJECTS)
        self.camera_rng = self.seeds.generator(Stream.CAMERA)
        self.fault_seed_sequence = self.seeds.sequence(Stream.FAULTS)

    @classmethod
    def from_file(cls, path: str | Path, seed: int, *, camera_mount: str | None = None) -> World:
        return cls(load_scene(path), seed, camera_mount=camera_mount, source=path)

    # --- building ------------------------------------------------------------------------------------
    def _build_table(self) -> None:
        table = self.config.table
        builder = self.scene.create_actor_builder()
        half = [table.size_m[0] / 2, table.size_m[1] / 2, table.size_m[2] / 2]
        material = sapien.physx.PhysxMaterial(table.friction, table.friction, 0.0)
        rgb = table.color if not isinstance(table.color, str) else None
        color = [*(rgb or COLOR_NAMES[str(table.color)]), 1.0]
        builder.add_box_collision(half_size=half, material=material)
        builder.add_box_visual(half_size=half, material=sapien.render.RenderMaterial(base_color=color, roughness=0.9))
        builder.set_initial_pose(sapien.Pose(p=[table.center_xy_m[0], table.center_xy_m[1], -half[2]]))
        self.table = builder.build_static(name="table")
        ground = self.scene.create_actor_builder()
        ground.add_plane_collision(sapien.Pose(p=[0, 0, -0.75], q=[0.7071068, 0, -0.7071068, 0]))
        ground.add_plane_visual(
            sapien.Pose(p=[0, 0, -0.75], q=[0.7071068, 0, -0.7071068, 0]),
            scale=[10, 10, 10],
            material=sapien.render.RenderMaterial(base_color=[0.35, 0.35, 0.38, 1]),
        )
        ground.build_static(name="floor")

    def _build_lights(self) -> None:
        for light in self.config.lights:
            if light.kind == "ambient":
                self.scene.set_ambient_light(list(light.color))
            elif light.kind == "directional":
                self.scene.add_directional_light(list(light.direction), list(light.color), shadow=light.shadow)
            else:
                self.scene.add_point_light(list(light.position_m), list(light.color), shadow=light.shadow)

    def settle(self, max_s: float = SETTLE_MAX_S) -> int:
        """Let the objects come to rest where they were drawn: step physics one control period at a time until
        every object is still (:data:`SETTLE_SPEED_M_S`, :data:`SETTLE_SPIN_RAD_S`) for
        :data:`SETTLE_STILL_TICKS` periods, or ``max_s`` of simulated time passed. Deterministic (no wall
        clock); the simulated time it takes passes on the world's clock before the run's first tick. The objects'
        motion is damped while they settle (:data:`SETTLE_ANGULAR_DAMPING`), the simulator's defaults restored
        after. Returns the physics steps taken. Primitives are drawn exactly resting, so scenes without meshes
        skip this."""
        bodies = [e.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent) for e in self.objects.values()]
        still, start = 0, self._physics_steps
        limit = start + round(max_s / self.dt_s)
        kept = [(b.get_angular_damping(), b.get_linear_damping()) for b in bodies]
        for b in bodies:  # they come to rest, as objects set on a table do (see SETTLE_ANGULAR_DAMPING)
            b.set_angular_damping(SETTLE_ANGULAR_DAMPING)
            b.set_linear_damping(SETTLE_LINEAR_DAMPING)
        while self._physics_steps < limit and still < SETTLE_STILL_TICKS:
            self.step_tick()
            calm = all(
                np.linalg.norm(b.get_linear_velocity()) < SETTLE_SPEED_M_S
                and np.linalg.norm(b.get_angular_velocity()) < SETTLE_SPIN_RAD_S
                for b in bodies
            )
            still = still + 1 if calm else 0
        for b, (angular, linear) in zip(bodies, kept, strict=True):  # the run's physics is the simulator's own
            b.set_angular_damping(angular)
            b.set_linear_damping(linear)
        log.debug("objects settled in %d physics steps", self._physics_steps - start)
        return self._physics_steps - start

    # --- time ----------------------------------------------------------------------------------------
    @property
    def dt_s(self) -> float:
        return self.config.physics.timestep_s

    @property
    def steps_per_tick(self) -> int:
        return max(1, round(1.0 / (self.config.physics.control_rate_hz * self.dt_s)))

    def now_ns(self) -> int:
        return self.clock.now_ns()

    @property
    def physics_steps(self) -> int:
        """Physics steps since this world was built."""
        return self._physics_steps

    def step(self, n: int = 1) -> None:
        """Advance physics by n steps of dt (the robot's controller runs before each)."""
        dt_ns = round(self.dt_s * 1e9)
        for _ in range(n):
            for feed in self.feeds:
                for placed in feed.due():
                    self._enter(placed)
            self.robot.before_physics_step()
            for belt in self.belts:
                belt.before_step(self.dt_s)
            self.scene.step()
            self.clock.advance_ns(dt_ns)
        self._physics_steps += n

    def _enter(self, placed: PlacedObject) -> None:
        """A feed's object enters: a new body set down where it was drawn, one of the run's objects from now on
        (the oracle, the judge and the camera see it; ``config.objects`` names it)."""
        name = placed.spec.name
        self.objects[name] = build_object(self.scene, placed)
        self.placed.append(placed)
        self.config = self.config.model_copy(update={"objects": (*self.config.objects, placed.spec)})
        self.entered[name] = placed.T_world_object
        log.debug("%s entered at %.3f s", name, self.clock.now_s())

    def step_tick(self) -> None:
        """Advance one control period (one behaviour-tree tick)."""
        self.step(self.steps_per_tick)
