"""A ChArUco board as a render-only SAPIEN object: on the gripper (eye-to-hand) or on the table (eye-in-hand).

The board is a textured quad mesh (RGBA texture, explicit UVs; a box visual would wrap the texture like a
cube atlas) with a white margin of half a square. Only its printed side is drawn (SAPIEN draws a triangle
from the side its right-hand normal faces): the side a camera looking along the board's +z sees.
Its true pose is ground truth: tests and the calibration command's judge read it, the calibration does not.
"""

from __future__ import annotations

import numpy as np
import sapien

from bt_grasp.geometry import Mat4, inv, make_T
from bt_grasp.interfaces import Mount
from bt_grasp.perception.calibration import BoardMount
from bt_grasp.perception.charuco import BoardSpec, board_image
from bt_grasp.sim.poses import to_pose
from bt_grasp.sim.world import World

#: the printed side of the board faces away from the flange, just beyond the finger tips (palm z = 0.10 m)
BOARD_STANDOFF_M = 0.11
_PX_PER_SQUARE = 96


def board_mesh(spec: BoardSpec) -> sapien.render.RenderShapeTriangleMesh:
    """The quad (with its margin) in the board frame, textured with the board image."""
    margin_px = _PX_PER_SQUARE // 2
    image = board_image(spec, _PX_PER_SQUARE, margin_px)
    rgba = np.dstack([image, image, image, np.full_like(image, 255)])
    texture = sapien.render.RenderTexture2D(np.ascontiguousarray(rgba), "R8G8B8A8Unorm", 5, "linear", "edge")
    material = sapien.render.RenderMaterial(base_color=[1.0, 1.0, 1.0, 1.0], roughness=0.9, metallic=0.0)
    material.base_color_texture = texture
    width, height = spec.size_m
    margin = spec.square_m * margin_px / _PX_PER_SQUARE
    x0, y0, x1, y1 = -margin, -margin, width + margin, height + margin
    vertices = np.array([[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]], dtype=np.float32)
    triangles = np.array([[0, 3, 2], [0, 2, 1]], dtype=np.uint32)  # right-hand normals along board -z
    normals = np.tile(np.array([[0.0, 0.0, -1.0]], dtype=np.float32), (4, 1))
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float32)
    return sapien.render.RenderShapeTriangleMesh(vertices, triangles, normals, uvs, material)


def default_T_palm_board(spec: BoardSpec) -> Mat4:
    """Board centred on the palm's axis, printed side facing away from the flange (board z = -palm z)."""
    R = np.diag([1.0, -1.0, -1.0])
    width, height = spec.size_m
    centre = np.array([0.0, 0.0, BOARD_STANDOFF_M])
    return make_T(R, centre - R @ np.array([width / 2, height / 2, 0.0]))


def default_T_world_board(spec: BoardSpec, centre_xy_m: tuple[float, float] = (0.40, 0.45)) -> Mat4:
    """Board lying printed side up on the table (0.5 mm above the top, no z-fighting)."""
    R = np.diag([1.0, -1.0, -1.0])
    width, height = spec.size_m
    centre = np.array([centre_xy_m[0], centre_xy_m[1], 0.0005])
    return make_T(R, centre - R @ np.array([width / 2, height / 2, 0.0]))


def attach_board_to_link(world: World, spec: BoardSpec, link_name: str = "gripper_palm",
                         T_link_board: Mat4 | None = None) -> Mat4:
    """Add the board as a visual of a robot link; returns its true pose in the link frame."""
    T = default_T_palm_board(spec) if T_link_board is None else T_link_board
    shape = board_mesh(spec)
    shape.set_local_pose(to_pose(T))
    body = sapien.render.RenderBodyComponent()
    body.attach(shape)
    body.set_name("charuco_board")
    entity = world.robot.links[link_name].entity
    entity.add_component(body)
    return T


def place_board_on_table(world: World, spec: BoardSpec, T_world_board: Mat4 | None = None) -> Mat4:
    """Add the board as a static visual lying on the table; returns its true pose in the world frame."""
    T = default_T_world_board(spec) if T_world_board is None else T_world_board
    shape = board_mesh(spec)
    body = sapien.render.RenderBodyComponent()
    body.attach(shape)
    entity = sapien.Entity()
    entity.set_name("charuco_board")
    entity.add_component(body)
    entity.set_pose(to_pose(T))
    world.scene.add_entity(entity)
    return T


def mount_calibration_board(world: World, spec: BoardSpec | None = None) -> BoardMount:
    """The one place a calibration board is mounted: on the gripper palm when the camera is eye-to-hand,
    on the table when it is eye-in-hand. Returns what a calibration may know: the board's spec and its
    nominal (design) pose, ``T_tool_board`` or ``T_base_board``. Removed again by ``world.reset``."""
    spec = spec or BoardSpec()
    if world.camera_mount == Mount.EYE_TO_HAND:
        # the board is screwed to the palm, which is bolted to tool0 with no offset: its design pose
        return BoardMount(spec, attach_board_to_link(world, spec, "gripper_palm"))
    return BoardMount(spec, inv(world.config.T_world_base()) @ place_board_on_table(world, spec))
