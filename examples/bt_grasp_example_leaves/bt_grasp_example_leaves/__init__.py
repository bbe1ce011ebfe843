"""An example bt_grasp plugin: ``GripperOpenAtLeast`` (a condition on the robot's gripper, with its own failure
reason) and ``Dwell`` (a wait in simulated time). Installed, bt_grasp finds it through the ``bt_grasp.leaves``
entry point; see docs/own-leaves.md."""
