"""One twin for the whole folder: ``bt-grasp twin`` in a process of its own, on a loopback address of its own.

ur_rtde's ports are fixed, so the address must be free of other twins (other engineers' test runs share this
machine): a free 127.x.y.z is found by binding every port first. The twin runs with ``--unlock-delay 0.5`` so a
protective-stop test does not wait a robot's 5 s (the 5 s rule itself is checked with it, in
``test_twin_ur_rtde.py``). Tests that change the twin's state put it back (program running, safety normal).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from bt_grasp.bench.twin_process import TwinProcess
from bt_grasp.bench.twin_process import start_twin as start_twin_process

REPO = Path(__file__).resolve().parents[2]

#: Wall-clock bounds. Issue 40's figures (a fault seen within one period + 50 ms, the period's 99th percentile under
#: twice 8 ms) are measured with ``BT_GRASP_STRICT_TIMING=1 pytest -s tests/twin/test_twin_faults.py
#: tests/twin/test_twin_rtde_guide.py`` (docs/twin.md), where the strict bounds are asserted. In ``make test`` the
#: same tests check what is seen (the fault, its state, no cycle lost: counted by the twin's own RTDE timestamps) and
#: bound the wall time generously: on this 2-core machine shared by several test runs a client's wake-up alone was
#: measured late by 75 ms (a gripper timeout of 58 ms seen after 75 ms), which is the load, not the twin.
STRICT_TIMING = os.environ.get("BT_GRASP_STRICT_TIMING") == "1"


def start_twin(tmp: Path, *extra: str, salt: int = 0) -> TwinProcess:
    """The tabletop twin on a free loopback address (the bench's own start-up: ``bt_grasp.bench.twin_process``)."""
    return start_twin_process("scenes/tabletop.yaml", tmp, "--unlock-delay", "0.5", *extra, salt=salt, repo=REPO)


@pytest.fixture(scope="session")
def twin(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TwinProcess]:
    pytest.importorskip("rtde_control", reason="ur_rtde is not installed (pip install -e '.[ur]')")
    started = start_twin(tmp_path_factory.mktemp("twin"))
    yield started
    code = started.stop()
    assert code == 0, started.log()[-3000:]
