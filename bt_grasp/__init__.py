"""bt_grasp: behaviour-tree vision-guided grasping."""
