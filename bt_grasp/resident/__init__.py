"""A resident episode process: `bt-grasp run --resident` hands its episode to a warm process that stays up.

A one-off `bt-grasp run` spends most of its wall time before the first tick: imports, and SAPIEN's renderer
start-up on the first picture (3.5-7 s of CPU on lavapipe, per process; SAPIEN and lavapipe offer no cache that
survives the process: see docs/campaigns.md, "Start-up"). The resident process pays that once and runs each
following episode on its warm world (``bt_grasp.episode.WarmWorlds``, the campaign workers' reuse), so a
second run costs the episode itself.
"""
