"""The scene's movable objects (``objects:``): what each is, where it is drawn, how its pose is randomised.

Frames: world frame, z up, origin on the table top. An object's drawn pose is the simulator's secret: the
pipeline finds objects with its camera; only the simulator, the judge and tests read these poses.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, PrivateAttr, field_validator, model_validator

from bt_grasp.errors import ConfigError
from bt_grasp.files.config import StrictModel
from bt_grasp.scene.colors import check_color, rgb_of
from bt_grasp.scene.mesh_geometry import MeshGeometry

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Range = tuple[float, float]


class ObjectPose(StrictModel):
    xy_m: tuple[float, float]
    yaw_deg: float = 0.0


class Randomize(StrictModel):
    x_m: Range = (0.0, 0.0)
    y_m: Range = (0.0, 0.0)
    yaw_deg: Range = (0.0, 0.0)

    @field_validator("x_m", "y_m", "yaw_deg")
    @classmethod
    def _ordered(cls, value: Range) -> Range:
        if value[0] > value[1]:
            raise ValueError("a range is [low, high] with low <= high")
        return value


class Choose(StrictModel):
    """(scene key ``choose``) A seeded subset of the objects: ``count`` of the objects named in ``among`` (all
    objects when not given), drawn from the run's seed; objects not in ``among`` are always there."""

    among: tuple[str, ...] | None = None
    count: Annotated[int, Field(ge=0)] | tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]]

    @field_validator("count")
    @classmethod
    def _ordered(cls, value: int | tuple[int, int]) -> int | tuple[int, int]:
        if isinstance(value, tuple) and value[0] > value[1]:
            raise ValueError("count is a number or [low, high] with low <= high")
        return value

    @property
    def count_range(self) -> tuple[int, int]:
        return (self.count, self.count) if isinstance(self.count, int) else self.count


#: the mesh file formats a ``shape: mesh`` object may name (trimesh reads them; COLLADA through pycollada)
MESH_SUFFIXES: tuple[str, ...] = (".obj", ".stl", ".ply", ".glb", ".gltf", ".dae")
PRIMITIVE_SHAPES: tuple[str, ...] = ("box", "cylinder", "sphere")
#: a mesh object's colour when the scene gives none and its file has no material colour
DEFAULT_MESH_RGB: tuple[float, float, float] = (0.6, 0.6, 0.6)
#: how a mesh or URDF object is set down (``rest_pose``): as its file is oriented, or one of its stable rest
#: poses drawn from the seed (``stable``: with the chance it lands so when dropped; ``any_stable``: every distinct
#: rest pose equally likely). See :mod:`bt_grasp.scene.layout`.
RestPoseRule = Literal["modelled", "stable", "any_stable"]
#: what a URDF object collides as (``collision``): the collision parts its file names (``file``), or the drawn
#: mesh (``from_visual``: for object sets whose collision files are coarse hulls, a mug's cup filled solid),
#: made convex pieces by the same cached decomposition (:mod:`bt_grasp.scene.mesh_cache`)
CollisionSource = Literal["file", "from_visual"]


class SceneObject(StrictModel):
    """One movable object. Primitives (``box``, ``cylinder``, ``sphere``) give ``size_m`` and ``color``;
    a ``mesh`` gives ``mesh: FILE`` (relative to the scene file) and may give ``scale``, a colour (else the
    file's own material) and ``mass_kg`` or ``density_kg_m3``; a ``urdf`` gives ``urdf: FILE`` (one rigid body:
    its collision and visual parts, and its mass unless the scene gives one). A mesh's or URDF's
    geometry is read and checked when the scene loads (:func:`bt_grasp.scene.meshes.attach_geometry`) and
    is then :attr:`geometry`."""

    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_\-]*$")]
    shape: Literal["box", "cylinder", "sphere", "mesh", "urdf"]
    size_m: tuple[PositiveFloat, ...] | None = None  # box: x y z; cylinder: radius height; sphere: radius
    mesh: Annotated[str, Field(min_length=1)] | None = None  # shape: mesh; OBJ, STL, PLY, GLB, GLTF or DAE file
    urdf: Annotated[str, Field(min_length=1)] | None = None  # shape: urdf; a URDF of one rigid body
    scale: PositiveFloat | tuple[PositiveFloat, PositiveFloat, PositiveFloat] = 1.0  # mesh units -> metres
    color: str | tuple[float, float, float] | None = None  # primitives: required; meshes: else the file's
    mass_kg: PositiveFloat | None = None  # default 0.1 kg (a URDF: its <inertial> mass)
    density_kg_m3: PositiveFloat | None = None  # meshes only: mass from the collision volume
    friction: NonNegFloat = 0.8
    pose: ObjectPose
    randomize: Randomize = Randomize()
    rest_pose: RestPoseRule = "modelled"  # mesh and urdf objects: how the object is set down (drawn per seed)
    collision: CollisionSource = "file"  # urdf objects: collide as the collision parts (file) or the drawn mesh
    _geometry: MeshGeometry | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _keys_match_shape(self) -> SceneObject:
        if self.shape in PRIMITIVE_SHAPES:
            expected = {"box": 3, "cylinder": 2, "sphere": 1}[self.shape]
            if self.size_m is None:
                raise ValueError(f"a {self.shape} needs size_m with {expected} numbers")
            if len(self.size_m) != expected:
                raise ValueError(f"a {self.shape} needs size_m with {expected} numbers, got {len(self.size_m)}")
            if self.color is None:
                raise ValueError(f"a {self.shape} needs a color")
            for key in ("mesh", "urdf", "density_kg_m3"):
                if getattr(self, key) is not None:
                    raise ValueError(f"'{key}' is for mesh or urdf objects, not a {self.shape}")
            if self.scale != 1.0:
                raise ValueError(f"'scale' is for mesh or urdf objects, not a {self.shape} (give size_m)")
            if self.rest_pose != "modelled":
                raise ValueError(f"'rest_pose' is for mesh or urdf objects, not a {self.shape}")
            if self.collision != "file":
                raise ValueError(f"'collision' is for urdf objects, not a {self.shape} (it collides as its shape)")
            return self
        file_key = self.shape  # "mesh" or "urdf"
        other = "urdf" if file_key == "mesh" else "mesh"
        if getattr(self, file_key) is None:
            raise ValueError(f"a {self.shape} object needs '{file_key}: FILE' (relative to the scene file)")
        if getattr(self, other) is not None:
            raise ValueError(f"a {self.shape} object takes '{file_key}', not '{other}'")
        if self.size_m is not None:
            raise ValueError(f"a {self.shape} object's size comes from its file and 'scale', not size_m")
        if self.mass_kg is not None and self.density_kg_m3 is not None:
            raise ValueError("give mass_kg or density_kg_m3, not both")
        if self.shape == "mesh" and self.collision != "file":
            raise ValueError("'collision: from_visual' is for urdf objects: a mesh object collides as its drawn "
                             "mesh already")
        if self.mesh is not None and not self.mesh.lower().endswith(MESH_SUFFIXES):
            raise ValueError(f"mesh file '{self.mesh}' is not one of {', '.join(MESH_SUFFIXES)}")
        return self

    @field_validator("color")
    @classmethod
    def _known_color(
        cls, value: str | tuple[float, float, float] | None
    ) -> str | tuple[float, float, float] | None:
        return None if value is None else check_color(value)

    @property
    def is_mesh(self) -> bool:
        """True for ``mesh`` and ``urdf`` objects (their geometry comes from files)."""
        return self.shape not in PRIMITIVE_SHAPES

    @property
    def scale_xyz(self) -> tuple[float, float, float]:
        s = self.scale
        return (float(s), float(s), float(s)) if isinstance(s, int | float) else (s[0], s[1], s[2])

    @property
    def geometry(self) -> MeshGeometry:
        """The mesh read from this object's file (mesh and urdf objects of a loaded scene only)."""
        if self._geometry is None:
            raise ConfigError(self.name, "a mesh object's geometry is read by load_scene; load the scene file")
        return self._geometry

    def with_geometry(self, geometry: MeshGeometry) -> SceneObject:
        """Attach the geometry the scene loader read (done once, at load)."""
        self._geometry = geometry
        return self

    @property
    def mass_or_default_kg(self) -> float | None:
        """The mass to give the body; None: from ``density_kg_m3`` and the collision volume."""
        if self.mass_kg is not None:
            return self.mass_kg
        if self.density_kg_m3 is not None:
            return None
        if self.shape == "urdf" and self._geometry is not None and self._geometry.mass_kg is not None:
            return self._geometry.mass_kg
        return 0.1

    @property
    def size_xyz_m(self) -> tuple[float, float, float]:
        """The object's extents along its own x, y, z (a mesh: its scaled bounding box)."""
        if self.is_mesh:
            lo, hi = self.geometry.bounds_m
            return (hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2])
        assert self.size_m is not None
        if self.shape == "box":
            return (self.size_m[0], self.size_m[1], self.size_m[2])
        d = 2 * self.size_m[0]
        return (d, d, self.height_m)

    @property
    def dims_m(self) -> tuple[float, ...]:
        """``size_m`` for a primitive; a mesh's scaled bounding-box extents (x, y, z) otherwise."""
        if self.is_mesh:
            return self.size_xyz_m
        assert self.size_m is not None
        return self.size_m

    @property
    def height_m(self) -> float:
        if self.is_mesh:
            lo, hi = self.geometry.bounds_m
            return hi[2] - lo[2]
        assert self.size_m is not None
        return {"box": self.size_m[-1], "cylinder": self.size_m[-1], "sphere": 2 * self.size_m[0]}[self.shape]

    @property
    def rgb(self) -> tuple[float, float, float]:
        if self.color is not None:
            return rgb_of(self.color)
        if self._geometry is not None and self._geometry.rgb is not None:
            return self._geometry.rgb
        return DEFAULT_MESH_RGB
