"""Reading a URDF that describes one movable object, the way object sets ship them (YCB-style, pybullet's,
Gazebo's, ROS packages'), into typed parts: what to draw and what collides, each placed in the object's frame.

What is accepted (everything else is one sentence naming the URDF's line):

- one rigid body: links joined by ``fixed`` joints are one body (their ``<origin>`` composes); links with no
  ``<visual>`` or ``<collision>`` are frames only (a ``center_of_mass`` marker) and are left out; a ``floating``
  joint from a link with no geometry is Gazebo's way to say "free body" (``<link name="world"/>``) and is left
  out too, and so is a geometry-less root fixed to the object (a ``world`` placing it somewhere): the object's
  frame is then its first link with geometry. A ``revolute``, ``prismatic``, ``continuous`` or ``planar``
  joint is an articulated object: refused.
- any number of ``<visual>`` and ``<collision>`` elements, each with its own ``<origin xyz rpy>``; geometry a
  ``<mesh filename scale>`` or a ``<box>``, ``<cylinder>`` or ``<sphere>``. Without ``<collision>`` the visuals
  collide; without ``<visual>`` the collisions are drawn.
- mesh file names relative to the URDF, absolute, ``file://``, or ``package://NAME/PATH``
  (:mod:`bt_grasp.scene.mesh_paths`).
- ``<material>`` colours, inline or named at the top of the file; the mass of ``<inertial><mass>`` (summed over
  the body's links). The inertial ``<origin>`` and ``<inertia>`` are not used: the simulator takes the centre of
  mass and inertia from the collision shapes at one density. Simulator-specific tags (``<contact>``,
  ``<gazebo>``) are ignored.

The object's frame is the body's root link's frame (its first link with geometry, below frame-only ones).
Nothing is read but the URDF itself here; the meshes are read by :mod:`bt_grasp.scene.meshes`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from bt_grasp.errors import ConfigError
from bt_grasp.geometry import T_from_xyz_rpy
from bt_grasp.scene.mesh_geometry import Vec3
from bt_grasp.scene.mesh_paths import MeshResolver

#: joint types that keep the object one rigid body
RIGID_JOINTS = ("fixed",)
#: the most links (and joints) an object's URDF may have; its link tree is walked by iteration, never recursion
#: (a 1,200-link chain of fixed joints was a RecursionError traceback)
MAX_LINKS = 10_000


@dataclass(frozen=True)
class MeshRef:
    """A mesh file and the URDF's ``scale`` for it (file units -> metres, before the scene's ``scale``)."""

    path: Path
    scale: Vec3


@dataclass(frozen=True)
class Primitive:
    """A URDF box (``dims_m``: x, y, z sizes), cylinder (radius, length along z) or sphere (radius)."""

    kind: Literal["box", "cylinder", "sphere"]
    dims_m: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class UrdfPart:
    """One ``<visual>`` or ``<collision>``: its geometry, placed in the object's frame, and its colour."""

    geometry: MeshRef | Primitive
    T_object_part: np.ndarray  # 4x4, the part's frame in the object's (root link's) frame
    rgba: tuple[float, float, float, float] | None
    line: int | None


@dataclass(frozen=True, eq=False)
class UrdfObject:
    visuals: tuple[UrdfPart, ...]
    collisions: tuple[UrdfPart, ...]
    mass_kg: float | None  # the body's links' <inertial><mass>, summed; None when no link gives one


def read_urdf(data: bytes, path: Path, packages: Mapping[str, Path] | None = None) -> UrdfObject:
    """The object a URDF describes (see the module's rules); :class:`ConfigError` naming ``path`` and a line."""
    root = _parse(data, path)
    if root.tag != "robot":
        raise ConfigError(path, f"is not a URDF: its root element is <{root.tag}>, not <robot>", where=_line(root))
    materials = _named_materials(root, path)
    links = _links(root, path)
    has_geometry = {name: _has_geometry(el) for name, el in links.items()}
    if not any(has_geometry.values()):
        raise ConfigError(path, "has no <visual> or <collision> in any link; a URDF object needs geometry",
                          where=_line(root))
    parent_of = _rigid_tree(root, links, has_geometry, path)
    body_root = _body_root(parent_of, has_geometry, links, path)
    T_root_link = _link_frames(body_root, parent_of, links, path)
    resolver = MeshResolver(path, packages or {})
    visuals: list[UrdfPart] = []
    collisions: list[UrdfPart] = []
    masses: list[float] = []
    for name, T in T_root_link.items():
        link = links[name]
        visuals += [_part(el, T, path, resolver, materials) for el in link.findall("visual")]
        collisions += [_part(el, T, path, resolver, materials) for el in link.findall("collision")]
        mass = _mass(link, path)
        if mass is not None:
            masses.append(mass)
    if not collisions:
        collisions = visuals
    if not visuals:
        visuals = collisions
    return UrdfObject(tuple(visuals), tuple(collisions), sum(masses) if masses else None)


# -- XML -----------------------------------------------------------------------------------------------------

def _parse(data: bytes, path: Path) -> Any:
    import defusedxml
    from defusedxml.ElementTree import DefusedXMLParser, ParseError

    class _LineRecordingParser(DefusedXMLParser):  # type: ignore[misc]
        def _start(self, tag: str, attr_list: Any) -> Any:
            element = super()._start(tag, attr_list)
            element.sourceline = self.parser.CurrentLineNumber
            return element

    parser = _LineRecordingParser(forbid_dtd=True, forbid_entities=True, forbid_external=True)
    try:
        parser.feed(data)
        return parser.close()
    except ParseError as exc:
        line = exc.position[0] if getattr(exc, "position", None) else None
        message = re.sub(r": line \d+, column \d+$", "", str(exc))
        raise ConfigError(path, f"is not a readable URDF (malformed XML: {message})", where=line) from None
    except (defusedxml.DTDForbidden, defusedxml.EntitiesForbidden, defusedxml.ExternalReferenceForbidden,
            defusedxml.NotSupportedError):
        raise ConfigError(path, "is not a readable URDF: DTDs, entities and external references are not allowed",
                          where=parser.parser.CurrentLineNumber) from None


def _line(element: Any) -> int | None:
    return getattr(element, "sourceline", None)


def _has_geometry(link: Any) -> bool:
    return link.find("visual") is not None or link.find("collision") is not None


def _links(root: Any, path: Path) -> dict[str, Any]:
    links: dict[str, Any] = {}
    found, joints = root.findall("link"), root.findall("joint")
    if len(found) > MAX_LINKS or len(joints) > MAX_LINKS:
        raise ConfigError(path, f"has {len(found):,} links and {len(joints):,} joints, more than the {MAX_LINKS:,} a "
                          "URDF object may have", where=_line(root))
    for el in found:
        name = el.get("name", "")
        if not name:
            raise ConfigError(path, "has a <link> without a name", where=_line(el))
        if name in links:
            raise ConfigError(path, f"has two links named '{name}'", where=_line(el))
        links[name] = el
    return links


def _rigid_tree(root: Any, links: dict[str, Any], has_geometry: dict[str, bool],
                path: Path) -> dict[str, tuple[str, Any]]:
    """child link -> (parent link, joint) for the fixed joints; other joints are refused or left out."""
    parent_of: dict[str, tuple[str, Any]] = {}
    for joint in root.findall("joint"):
        name, kind = joint.get("name", "?"), joint.get("type", "")
        parent = (joint.find("parent").get("link", "") if joint.find("parent") is not None else "")
        child = (joint.find("child").get("link", "") if joint.find("child") is not None else "")
        for end in (parent, child):
            if end not in links:
                raise ConfigError(path, f"joint '{name}' names link '{end}', which the file does not have",
                                  where=_line(joint))
        if kind == "floating" and not has_geometry[parent]:
            continue  # Gazebo's <link name="world"/> + floating joint: the child is a free body
        if kind not in RIGID_JOINTS:
            raise ConfigError(path, f"joint '{name}' is {kind or 'of no type'}: a URDF object must be one rigid body "
                              "(fixed joints only; articulated objects are not supported)", where=_line(joint))
        if child in parent_of:
            raise ConfigError(path, f"link '{child}' is the child of two joints", where=_line(joint))
        parent_of[child] = (parent, joint)
    return parent_of


def _top(name: str, parent_of: dict[str, tuple[str, Any]], path: Path, tops: dict[str, str]) -> str:
    """The root of ``name``'s tree, by walking up (iteration; every link on the way remembered in ``tops``)."""
    chain = [name]
    seen = {name}
    while chain[-1] not in tops and chain[-1] in parent_of:
        parent = parent_of[chain[-1]][0]
        if parent in seen:
            raise ConfigError(path, f"its fixed joints form a loop through link '{parent}'")
        seen.add(parent)
        chain.append(parent)
    top = tops.get(chain[-1], chain[-1])
    for link in chain:
        tops[link] = top
    return top


def _body_root(parent_of: dict[str, tuple[str, Any]], has_geometry: dict[str, bool], links: dict[str, Any],
               path: Path) -> str:
    """The root link of the fixed-joint tree holding every link with geometry."""
    known: dict[str, str] = {}
    tops = {name: _top(name, parent_of, path, known) for name, geo in has_geometry.items() if geo}
    roots = sorted(set(tops.values()))
    if len(roots) > 1:
        a, b = (next(n for n, t in tops.items() if t == r) for r in roots[:2])
        raise ConfigError(path, f"has {len(roots)} separate bodies (links '{a}' and '{b}' are not joined by fixed "
                          "joints); a URDF object must be one rigid body", where=_line(links[b]))
    root = roots[0]
    holding = _holding_geometry(parent_of, has_geometry)
    children: dict[str, list[str]] = {}
    for child, (parent, _joint) in parent_of.items():
        children.setdefault(parent, []).append(child)
    while not has_geometry[root]:  # a frame-only root (a 'world' fixed to the object): the object starts below it
        below = [c for c in children.get(root, []) if c in holding]
        if len(below) != 1:
            break
        root = below[0]
    return root


def _holding_geometry(parent_of: dict[str, tuple[str, Any]], has_geometry: dict[str, bool]) -> set[str]:
    """The links that have geometry or have a link with geometry below them (through fixed joints): each link
    with geometry marks its ancestors, walking up until a link already marked (iteration, linear in the links)."""
    holding: set[str] = set()
    for name, geo in has_geometry.items():
        while geo and name not in holding:
            holding.add(name)
            if name not in parent_of:
                break
            name = parent_of[name][0]
    return holding


def _link_frames(body_root: str, parent_of: dict[str, tuple[str, Any]], links: dict[str, Any],
                 path: Path) -> dict[str, np.ndarray]:
    """Every link of the body (in file order) -> its frame in the root link's frame (each link's chain up to a
    link already placed is walked by iteration, then composed down)."""
    frames: dict[str, np.ndarray] = {body_root: np.eye(4)}
    off_body: set[str] = set()  # links of another tree (a geometry-less frame not joined to the body)
    for name in links:
        chain: list[str] = []
        on_chain: set[str] = set()
        link = name
        while link not in frames and link not in off_body and link in parent_of and link not in on_chain:
            chain.append(link)
            on_chain.add(link)
            link = parent_of[link][0]
        if link not in frames:
            off_body.update(chain)
            off_body.add(link)
            continue
        for child in reversed(chain):
            frames[child] = frames[parent_of[child][0]] @ _origin(parent_of[child][1], path)
    return {name: frames[name] for name in links if name in frames}


# -- parts -----------------------------------------------------------------------------------------------------

def _numbers(text: str | None, count: int, what: str, path: Path, element: Any, default: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in (text if text is not None else default).replace(",", " ").split())
    except ValueError:
        values = ()
    if len(values) != count or not all(np.isfinite(v) for v in values):
        raise ConfigError(path, f"<{element.tag}> {what} {_quoted(text)} must be {count} numbers",
                          where=_line(element))
    return values


def _quoted(text: str | None) -> str:
    """An attribute's text as a sentence quotes it: at most 80 characters of it."""
    shown = "" if text is None else text
    return repr(shown if len(shown) <= 80 else shown[:77] + "...")


def _origin(element: Any, path: Path) -> np.ndarray:
    origin = element.find("origin")
    if origin is None:
        return np.eye(4)
    xyz = _numbers(origin.get("xyz"), 3, "xyz", path, origin, "0 0 0")
    rpy = _numbers(origin.get("rpy"), 3, "rpy", path, origin, "0 0 0")
    return T_from_xyz_rpy(list(xyz), list(rpy))


def _rgba(material: Any, path: Path) -> tuple[float, float, float, float] | None:
    color = material.find("color")
    if color is None:
        return None
    values = _numbers(color.get("rgba"), 4, "rgba", path, color, "")
    if not all(0.0 <= v <= 1.0 for v in values):
        raise ConfigError(path, f"<color> rgba {_quoted(color.get('rgba'))} must be four numbers from 0 to 1",
                          where=_line(color))
    return (values[0], values[1], values[2], values[3])


def _named_materials(root: Any, path: Path) -> dict[str, tuple[float, float, float, float] | None]:
    return {el.get("name", ""): _rgba(el, path) for el in root.findall("material")}


def _part(element: Any, T_root_link: np.ndarray, path: Path, resolver: MeshResolver,
          materials: dict[str, tuple[float, float, float, float] | None]) -> UrdfPart:
    geometry = element.find("geometry")
    shapes = [c for c in (geometry if geometry is not None else []) if isinstance(c.tag, str)]
    if len(shapes) != 1:
        raise ConfigError(path, f"<{element.tag}> needs a <geometry> with one mesh, box, cylinder or sphere",
                          where=_line(element))
    shape = shapes[0]
    rgba = None
    material = element.find("material")
    if material is not None:
        rgba = _rgba(material, path) or materials.get(material.get("name", ""))
    return UrdfPart(_geometry(shape, path, resolver), T_root_link @ _origin(element, path), rgba,
                    _line(shape))


def _geometry(shape: Any, path: Path, resolver: MeshResolver) -> MeshRef | Primitive:
    def positive(values: tuple[float, ...]) -> tuple[float, ...]:
        if not all(v > 0 for v in values):
            raise ConfigError(path, f"<{shape.tag}> sizes must be positive", where=_line(shape))
        return values

    if shape.tag == "mesh":
        scale = positive(_numbers(shape.get("scale"), 3, "scale", path, shape, "1 1 1"))
        return MeshRef(resolver.resolve(shape.get("filename", ""), _line(shape)), (scale[0], scale[1], scale[2]))
    if shape.tag == "box":
        return Primitive("box", positive(_numbers(shape.get("size"), 3, "size", path, shape, "")))
    if shape.tag == "cylinder":
        radius = positive(_numbers(shape.get("radius"), 1, "radius", path, shape, ""))
        length = positive(_numbers(shape.get("length"), 1, "length", path, shape, ""))
        return Primitive("cylinder", radius + length)
    if shape.tag == "sphere":
        return Primitive("sphere", positive(_numbers(shape.get("radius"), 1, "radius", path, shape, "")))
    raise ConfigError(path, f"<{shape.tag}> geometry is not supported (mesh, box, cylinder or sphere)",
                      where=_line(shape))


def _mass(link: Any, path: Path) -> float | None:
    mass = link.find("inertial/mass")
    if mass is None:
        return None
    try:
        value = float(mass.get("value", "nan"))
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise ConfigError(path, f"link mass is {_quoted(mass.get('value'))}; a mass must be a positive number of kg",
                          where=_line(mass))
    return value
