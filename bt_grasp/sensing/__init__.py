"""Perception on any camera source, with no motion: composes a source (a RealSense recording, a live RealSense
device, or a simulated scene played through pyrealsense2's software device), where each frame is in the base frame
(a calibration, and for a wrist camera the tool pose of each frame), the perception pipeline, grasp ranking, and the
MCAP log. The command line's ``perceive``, ``camera record`` and ``tree run --dry --camera`` call it.

* :mod:`~bt_grasp.sensing.source_spec` / :mod:`~bt_grasp.sensing.open_source`: what a SOURCE names, and opening it;
* :mod:`~bt_grasp.sensing.scene_camera`: the simulated D435 as a live RealSense device;
* :mod:`~bt_grasp.sensing.placement`: where each frame is (base frame, or the camera's own without calibration);
* :mod:`~bt_grasp.sensing.perceive_frame` / :mod:`~bt_grasp.sensing.report`: one frame's objects and grasps;
* :mod:`~bt_grasp.sensing.perceive_log`: the log Foxglove shows;
* :mod:`~bt_grasp.sensing.record_scene`: recordings written from the simulator;
* :mod:`~bt_grasp.sensing.dry_camera`: a tree's perception leaves on recorded frames;
* :mod:`~bt_grasp.sensing.compare`: recordings against the simulator, scene by scene.
"""
