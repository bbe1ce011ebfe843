"""A cell file seen as the scene the leaves read: the installation without objects.

The robot leaves read their cell's settings from a :class:`bt_grasp.scene.format.Scene` (the control rate, the home
pose, the table, the fixtures, the workspace, the camera's nominal mounting). A real cell's come from its cell file
(``bt_grasp.cell.format``); :func:`scene_for_cell` writes them in the scene's terms: the world frame's origin on the
table top right above the base (z up, axes as the base's), so the base stands ``table height`` below it; no objects
(they come from the camera), no noise model (nothing is simulated), no goal.
"""

from __future__ import annotations

from bt_grasp.cell.format import Cell
from bt_grasp.scene.format import Camera, DepthNoise, EyeInHand, EyeToHand, Physics, RobotMount, Scene, Table, Workspace

#: the table is drawn and planned around as a slab this thick under its top
TABLE_THICKNESS_M = 0.04


def scene_for_cell(cell: Cell) -> Scene:
    """The scene a real cell's leaves read (see the module docstring)."""
    h = cell.table_plane.height_m
    plane = cell.table_plane
    box = cell.workspace

    def up(p: tuple[float, float, float]) -> tuple[float, float, float]:
        return (p[0], p[1], p[2] - h)

    camera = cell.camera
    e2h = camera.eye_to_hand
    eih = camera.eye_in_hand
    scene_camera = Camera(
        model=camera.model, width_px=camera.width_px, height_px=camera.height_px, mount=camera.mount,
        eye_to_hand=EyeToHand() if e2h is None else EyeToHand(position_m=up(e2h.position_m),
                                                              look_at_m=up(e2h.look_at_m), roll_deg=e2h.roll_deg),
        eye_in_hand=EyeInHand() if eih is None else EyeInHand(parent_link=eih.parent_link, xyz_m=eih.xyz_m,
                                                              rpy_deg=eih.rpy_deg),
        noise=DepthNoise(enabled=False),
    )
    return Scene(
        version=2,
        name=cell.name,
        physics=Physics(control_rate_hz=cell.arm.control_rate_hz),
        table=Table(size_m=(plane.x_m[1] - plane.x_m[0], plane.y_m[1] - plane.y_m[0], TABLE_THICKNESS_M),
                    center_xy_m=((plane.x_m[0] + plane.x_m[1]) / 2, (plane.y_m[0] + plane.y_m[1]) / 2)),
        robot=RobotMount(base_xyz_m=(0.0, 0.0, -h), home_q_rad=cell.arm.home_q_rad),
        camera=scene_camera,
        workspace=Workspace(x_m=(box.min_m[0], box.max_m[0]), y_m=(box.min_m[1], box.max_m[1]),
                            z_max_m=box.objects_up_to_m),
        fixtures=cell.fixtures,
    )
