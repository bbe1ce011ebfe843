"""The scene model: what a scene file (``scenes/*.yaml``) says, as typed, strictly validated data.

One concept a module, no simulator (``bt_grasp.sim`` builds the world from these types; nothing else
re-implements them):

- :mod:`bt_grasp.scene.format`: the file itself (version, physics, table, robot mount, camera, lights,
  workspace) and :func:`~bt_grasp.scene.format.load_scene`, with the cross-reference checks;
- :mod:`bt_grasp.scene.objects`: the movable objects (primitive shapes, meshes, URDFs) and their drawn poses;
- :mod:`bt_grasp.scene.layout`: what a seed draws before the poses (the subset, the rest poses);
- :mod:`bt_grasp.scene.fixture_base`, :mod:`bt_grasp.scene.fixtures`, :mod:`bt_grasp.scene.conveyor`: static
  fixtures (trays, bins, markers, walls, the conveyor);
- :mod:`bt_grasp.scene.goals`: the goal a scene declares; :mod:`bt_grasp.scene.run_goal`: the goal of one run
  (from a command line, or a scene plus the run's blackboard);
- :mod:`bt_grasp.scene.meshes` and :mod:`bt_grasp.scene.mesh_cache`: mesh files read and checked, and their
  collision shapes (convex hull or convex decomposition) cached on disk.

Imports inside the package point one way: ``format -> (objects, fixtures, goals)``,
``fixtures -> (conveyor -> fixture_base)``, ``run_goal -> (format, goals)``, ``layout -> (format, objects)``.
This file imports nothing, so importing one module does not load the others.
"""
