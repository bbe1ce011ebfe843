"""Third-party submodules bt_grasp never uses, loaded only if something touches them (issue 27: memory, start-up).

``import open3d`` runs ``import open3d.visualization``, whose ``draw_plotly`` imports plotly and dash (and
through dash flask and werkzeug): ~42 MiB resident and 0.3-0.7 s of a one-off run's start-up, for drawing
functions no part of bt_grasp calls. :func:`defer_unused_submodules` puts a finder in front of Python's
import system that gives each module named in :data:`DEFERRED` a lazy loader
(:class:`importlib.util.LazyLoader`): the module object exists at once, and its code runs on the first
attribute anyone reads from it (``open3d.visualization.draw_geometries`` still works, one import later).
Nothing else changes: every other module loads as before, and no module's code is skipped for good.

Called by ``bt_grasp.perception`` (the package that imports open3d), before open3d is imported.
``tests/test_slim_imports.py`` checks both halves: the pipeline's modules load no dash, and the deferred
module still works when used.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import sys
from collections.abc import Sequence
from types import ModuleType

#: module name -> why bt_grasp does not need it at import (what it would load)
DEFERRED: dict[str, str] = {
    "open3d.visualization": "open3d's drawing helpers; draw_plotly imports plotly and dash (~42 MiB, 0.3-0.7 s)",
}


class _DeferringFinder(importlib.abc.MetaPathFinder):
    """Finds the modules of DEFERRED the usual way and wraps their loader in a LazyLoader."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in DEFERRED:
            return None
        spec = importlib.machinery.PathFinder.find_spec(fullname, path, target)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return None  # not a plain module on disk: let the import system load it as it would
        spec.loader = importlib.util.LazyLoader(spec.loader)
        return spec


def defer_unused_submodules() -> None:
    """Install the deferring finder once per process (idempotent; modules already imported stay as they are)."""
    if not any(isinstance(finder, _DeferringFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, _DeferringFinder())
