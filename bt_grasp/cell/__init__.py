"""Cell files: a real (or twin) work cell's installation data (``bt_grasp.cell.format``)."""
