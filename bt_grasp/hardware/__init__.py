"""Real hardware: the one package that imports device libraries (pyrealsense2, ur_rtde's modules).

Every device library is imported on first use (:func:`bt_grasp.hardware.realsense_lib.pyrealsense2`,
:func:`bt_grasp.hardware.ur_lib.ur_rtde`), never when bt_grasp or a command starts: the package imports, and every
command that needs no device runs, without the ``realsense``/``hardware`` extras. Asking for a device without its
library is one sentence and exit code 2.

A real cell (``docs/real-cell.md``):

* :mod:`~bt_grasp.hardware.ur_arm`: :class:`UrArm`, the :class:`bt_grasp.interfaces.Robot` of a UR through ur_rtde
  (servoJ streaming, the controller's state each period, the watchdog, stops) with
  :mod:`~bt_grasp.hardware.robotiq_client`'s Robotiq 2F-85 as its gripper;
* :mod:`~bt_grasp.hardware.cell_faults`: every way the cell ends a run, as a typed reason;
* :mod:`~bt_grasp.hardware.wall_time`: the wall clock and stepper of a run on a cell (the only wall time a run reads);
* :mod:`~bt_grasp.hardware.twin_camera` and :mod:`~bt_grasp.hardware.twin_control`: a twin's camera (through a
  software device and :class:`RealSenseCamera`) and its control port; :mod:`~bt_grasp.hardware.ur_dashboard`: the
  dashboard, for benchmarks against a twin.

The package drives devices and plans nothing: safety before motion (every trajectory and every streamed target
checked) is :mod:`bt_grasp.motion.guard`, and a cell's devices are opened and joined to it by the composition,
:mod:`bt_grasp.episode.cell_devices` (``tests/hardware/test_hardware_floors.py``).

Cameras:

* :mod:`~bt_grasp.hardware.realsense_camera`: :class:`RealSenseCamera`, the :class:`bt_grasp.interfaces.Camera` of a
  live D435 or a recording, read through pyrealsense2's pipeline and aligned with its own ``rs.align``;
* :mod:`~bt_grasp.hardware.realsense_open`: opening a live device (by serial number, or the only one) or a file;
* :mod:`~bt_grasp.hardware.software_d435`: a ``pyrealsense2.software_device`` shaped like a D435, into which
  frames drawn elsewhere (the simulator) are fed: recorded with the library's recorder, or read as a live device;
* :mod:`~bt_grasp.hardware.recording_file` and :mod:`~bt_grasp.hardware.tool_poses`: the checks of a recording a
  user gives, and the tool poses an eye-in-hand recording carries beside it.
"""
