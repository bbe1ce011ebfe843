"""The controller twin: a scene's simulated cell served as a UR controller over UR's own protocols.

The unmodified ur_rtde library (RTDE on 30004, the dashboard on 29999, its control script uploaded to 30003)
and a Robotiq 2F-85 client (63352) drive the SAPIEN UR5 as they would drive a robot; the twin's own control port
injects faults, asks the physics judge for a verdict and renders the camera. It lives in ``bt_grasp.sim``
because it needs the simulator and the judge. A twin runs in real time (wall clock, ``realtime.py``); the rest
of bt_grasp stays on simulated time. ``docs/twin.md`` is the user's guide.

Modules: ``twin`` (composition), ``controller`` + ``arm`` + ``motion`` + ``kinematics`` (the controller),
``script_program`` + ``control_script`` + ``commands`` (ur_rtde's control script, run by its handshake),
``rtde_types`` + ``rtde_server`` + ``outputs`` + ``state`` (RTDE), ``dashboard``, ``script_port``,
``gripper_port`` + ``robotiq`` (the gripper; its models are ``bt_grasp.cell.grippers``), ``control_port`` +
``faults`` (the twin's own port), ``camera_worker`` (rendering in a process of its own) + ``camera_port`` (its frames
for a run), ``netio`` (sockets), ``realtime`` (the clock), ``plant`` (the SAPIEN side), ``config``.
"""

from bt_grasp.sim.twin.config import TwinConfig
from bt_grasp.sim.twin.twin import Twin

__all__ = ["Twin", "TwinConfig"]
