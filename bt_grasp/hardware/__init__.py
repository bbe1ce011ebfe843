"""Real hardware: the one package that imports device libraries (pyrealsense2 today; the real arm joins it).

Every device library is imported on first use (:func:`bt_grasp.hardware.realsense_lib.pyrealsense2`), never when
bt_grasp or a command starts: the package imports, and every command that needs no device runs, without the
``realsense`` extra. Asking for a RealSense camera without it is one sentence and exit code 2.

* :mod:`~bt_grasp.hardware.realsense_camera`: :class:`RealSenseCamera`, the :class:`bt_grasp.interfaces.Camera` of a
  live D435 or a recording, read through pyrealsense2's pipeline and aligned with its own ``rs.align``;
* :mod:`~bt_grasp.hardware.realsense_open`: opening a live device (by serial number, or the only one) or a file;
* :mod:`~bt_grasp.hardware.software_d435`: a ``pyrealsense2.software_device`` shaped like a D435, into which
  frames drawn elsewhere (the simulator) are fed: recorded with the library's recorder, or read as a live device;
* :mod:`~bt_grasp.hardware.recording_file` and :mod:`~bt_grasp.hardware.tool_poses`: the checks of a recording a
  user gives, and the tool poses an eye-in-hand recording carries beside it.
"""
