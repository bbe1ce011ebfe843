"""What the planner knows about the robot's surroundings, in the robot base frame.

A :class:`PlanningScene` holds the table and the fixtures (installation data from the scene file, never
from the simulator), obstacles as boxes or cylinders (from perception), optionally one ``allowed_object``:
the object being grasped, which may touch the finger pads at the end of an approach but nothing else, and
optionally one ``attached`` object: the object held in the gripper while it is carried, given in the frame
of the link it moves with, checked against every scene shape (not against the robot holding it).
Each shape names the robot links allowed to touch it (``touch_links``): the table lets ``base_link``
stand on it; the allowed object lets the fingers close on it.

Everything is frozen and hashable, so collision models built for a scene can be cached by the scene.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from bt_grasp.geometry import Mat4, make_T
from bt_grasp.scene.format import Scene

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]

FINGER_LINKS: tuple[str, ...] = ("left_finger", "right_finger")


def _pose_fields(T_base_shape: Mat4) -> tuple[Vec3, Quat]:
    T = np.asarray(T_base_shape, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise ValueError(f"a shape pose is a finite 4x4 transform, got {T!r}")
    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    xyz = (float(T[0, 3]), float(T[1, 3]), float(T[2, 3]))
    return xyz, (float(w), float(x), float(y), float(z))


@dataclass(frozen=True)
class Box:
    """A box centred on its pose; ``size_m`` is the full edge lengths along its x, y, z."""

    name: str
    size_m: Vec3
    xyz_m: Vec3 = (0.0, 0.0, 0.0)  # centre, base frame
    quat_wxyz: Quat = (1.0, 0.0, 0.0, 0.0)  # orientation, base frame
    touch_links: tuple[str, ...] = ()  # robot links allowed to touch this shape

    def __post_init__(self) -> None:
        if len(self.size_m) != 3 or not all(np.isfinite(s) and s > 0 for s in self.size_m):
            raise ValueError(f"box '{self.name}' needs three positive sizes, got {self.size_m}")

    @classmethod
    def at(cls, name: str, size_m: Vec3, T_base_box: Mat4, touch_links: tuple[str, ...] = ()) -> Box:
        xyz, quat = _pose_fields(T_base_box)
        return cls(name, tuple(float(s) for s in size_m), xyz, quat, touch_links)  # type: ignore[arg-type]

    @property
    def T_base_shape(self) -> Mat4:
        return _T(self.xyz_m, self.quat_wxyz)


@dataclass(frozen=True)
class Cylinder:
    """A cylinder centred on its pose, axis along its z."""

    name: str
    radius_m: float
    height_m: float
    xyz_m: Vec3 = (0.0, 0.0, 0.0)
    quat_wxyz: Quat = (1.0, 0.0, 0.0, 0.0)
    touch_links: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not (np.isfinite(self.radius_m) and self.radius_m > 0 and np.isfinite(self.height_m)
                and self.height_m > 0):
            raise ValueError(f"cylinder '{self.name}' needs a positive radius and height")

    @classmethod
    def at(cls, name: str, radius_m: float, height_m: float, T_base_cylinder: Mat4,
           touch_links: tuple[str, ...] = ()) -> Cylinder:
        xyz, quat = _pose_fields(T_base_cylinder)
        return cls(name, float(radius_m), float(height_m), xyz, quat, touch_links)

    @property
    def T_base_shape(self) -> Mat4:
        return _T(self.xyz_m, self.quat_wxyz)


Shape = Box | Cylinder


def _T(xyz: Vec3, quat_wxyz: Quat) -> Mat4:
    w, x, y, z = quat_wxyz
    R: NDArray[np.float64] = Rotation.from_quat([x, y, z, w]).as_matrix()
    return make_T(R, list(xyz))


@dataclass(frozen=True)
class PlanningScene:
    """The robot's surroundings in the base frame: table, obstacles, and the object being grasped."""

    table: Box | None = None
    obstacles: tuple[Shape, ...] = ()
    allowed_object: Shape | None = None  # may touch the finger pads (see ``touch_links``)
    attached: Shape | None = None  # the held object, its pose in ``attached_link``'s frame (not the base)
    attached_link: str = "tcp"
    names: tuple[str, ...] = field(init=False, default=())

    def __post_init__(self) -> None:
        shapes = self.shapes()
        names = tuple(s.name for s in shapes)
        if len(set(names)) != len(names):
            raise ValueError(f"planning-scene shapes need unique names, got {names}")
        object.__setattr__(self, "names", names)

    def shapes(self) -> tuple[Shape, ...]:
        out: list[Shape] = []
        if self.table is not None:
            out.append(self.table)
        out.extend(self.obstacles)
        if self.allowed_object is not None:
            out.append(self.allowed_object)
        return tuple(out)

    @classmethod
    def from_scene(cls, scene: Scene, obstacles: tuple[Shape, ...] = (),
                   allowed_object: Shape | None = None) -> PlanningScene:
        """The table and the fixtures' solid parts (the scene file's installation data), in the base frame."""
        return cls(table=table_box(scene), obstacles=fixture_boxes(scene) + tuple(obstacles),
                   allowed_object=allowed_object)

    def with_obstacles(self, *obstacles: Shape) -> PlanningScene:
        return replace(self, obstacles=self.obstacles + tuple(obstacles))

    def with_allowed_object(self, shape: Shape | None) -> PlanningScene:
        """The scene with ``shape`` as the grasped object; its ``touch_links`` default to the fingers."""
        if shape is not None and not shape.touch_links:
            shape = replace(shape, touch_links=FINGER_LINKS)
        return replace(self, allowed_object=shape)

    def with_attached(self, shape: Shape | None, link: str = "tcp") -> PlanningScene:
        """The scene with ``shape`` (posed in ``link``'s frame) carried by the robot."""
        return replace(self, attached=shape, attached_link=link)


def fixture_boxes(scene: Scene) -> tuple[Box, ...]:
    """The solid parts of the scene's fixtures (tray floors and walls, walls) in the robot base frame."""
    T_base_world = np.linalg.inv(scene.T_world_base())
    return tuple(
        Box.at(part.name, part.size_m, T_base_world @ part.T_world_part)
        for fixture in scene.fixtures
        for part in fixture.parts()
        if part.solid
    )


def table_box(scene: Scene) -> Box:
    """The table top as a box in the robot base frame; the robot's base link stands on it."""
    table = scene.table
    T_world_table = make_T(translation=[table.center_xy_m[0], table.center_xy_m[1], -table.size_m[2] / 2])
    T_base_table = np.linalg.inv(scene.T_world_base()) @ T_world_table
    size = (float(table.size_m[0]), float(table.size_m[1]), float(table.size_m[2]))
    return Box.at("table", size, T_base_table, touch_links=("base_link",))
