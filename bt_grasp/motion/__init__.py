"""Motion: kinematics (pinocchio), collision (coal), planning (OMPL), trajectories (ruckig), execution.

Nothing here imports the simulator: the robot is reached through :class:`bt_grasp.interfaces.Robot`.
"""
