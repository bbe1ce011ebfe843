"""The command line runs numpy's linear algebra on one OpenBLAS thread (issue 27: the spinning second thread
doubled perception's CPU inside a pick), unless the user chose otherwise; it must be set before numpy loads."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.process.numeric_threads import NUMERIC_ENV, use_one_blas_thread

_OPENBLAS = sorted((Path(np.__file__).parent.parent / "numpy.libs").glob("libscipy_openblas64_*.so"))

_PROBE = """
import ctypes, os, sys
{before}
import numpy
print(os.environ.get("OPENBLAS_NUM_THREADS"), ctypes.CDLL({lib!r}).scipy_openblas_get_num_threads64_())
"""


def _probe(before: str, env_value: str | None) -> list[str]:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if env_value is not None:
        env["OPENBLAS_NUM_THREADS"] = env_value
    code = _PROBE.format(before=before, lib=str(_OPENBLAS[0]))
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return done.stdout.split()


@pytest.mark.skipif(not _OPENBLAS, reason="numpy here does not bundle scipy-openblas")
@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: OpenBLAS starts one thread anyway")
def test_the_command_line_leaves_numpy_one_blas_thread() -> None:
    assert _probe("", None)[1] != "1"  # the probe can tell: without bt_grasp's CLI, a thread per core
    assert _probe("import bt_grasp.cli.main", None) == ["1", "1"]


@pytest.mark.skipif(not _OPENBLAS, reason="numpy here does not bundle scipy-openblas")
def test_a_users_choice_is_kept() -> None:
    assert _probe("import bt_grasp.cli.main", "2") == ["2", "2"]


def test_the_cli_module_sets_it_before_numpy_is_imported() -> None:
    code = "import sys, bt_grasp.cli.main as m; print('numpy' in sys.modules)"
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False"]


def test_use_one_blas_thread_sets_only_what_is_missing() -> None:
    environ: dict[str, str] = {}
    use_one_blas_thread(environ)
    assert environ == NUMERIC_ENV
    environ = {"OPENBLAS_NUM_THREADS": "4"}
    use_one_blas_thread(environ)
    assert environ == {"OPENBLAS_NUM_THREADS": "4"}
