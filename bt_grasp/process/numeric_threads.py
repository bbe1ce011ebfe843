"""One OpenBLAS thread per bt_grasp process: set in the environment before numpy is imported.

numpy and scipy run their linear algebra through OpenBLAS, which starts a thread per core and, after each call,
keeps its threads spin-waiting for the next one. A pick makes thousands of tiny calls (IK solves, 3x3
products) and a few medium ones (perception's RANSAC plane: (N, 3) @ (3, 32) products over ~30k points): on
two cores the spinning thread takes a core from the physics, the renderer and the other worker, and the
calls themselves are too small to gain from a second thread. Measured on a warm pick (CHANGELOG,
"Performance history"): perception's call 0.25 -> 0.11 s of process CPU, the pick's process CPU -20 %, the same tick
stream (fingerprints) with one thread or two.

The command line applies it first thing (``bt_grasp.cli.main``), campaign workers get it in their environment
(``bt_grasp.campaign.worker.WORKER_ENV``), and so does the resident process, started by the command line. A
value the user set is kept. It has no effect in a process that imported numpy already.
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

#: the environment of every bt_grasp process (set before numpy is imported)
NUMERIC_ENV: dict[str, str] = {"OPENBLAS_NUM_THREADS": "1"}


def use_one_blas_thread(environ: MutableMapping[str, str] = os.environ) -> None:
    """Put ``NUMERIC_ENV`` into ``environ``, keeping any value already there."""
    for key, value in NUMERIC_ENV.items():
        environ.setdefault(key, value)
