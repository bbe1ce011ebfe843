"""The Foxglove front end: everything a Foxglove viewer sees or sends, in one package.

- ``live``: the live server (Foxglove WebSocket protocol, ``foxglove-sdk``): a run's topics as they are written;
- ``control``: the bridge from Studio's Parameters and Publish panels to the control API (``bt_grasp.control``);
- ``layout``: the shipped layouts (``layouts/*.json``) and the control panels added to them;
- ``tree_layout``: the layout generated for a tree (one row per leaf, by path), for a log or a live run.

``recording/`` writes and reads logs; this package shows them. The only package that imports ``foxglove``
(the SDK); the loopback rule its servers follow is ``bt_grasp.files.hosts``.
"""
