"""Issue 40, done-when 3: each fault on demand is observable by a ur_rtde client within one controller period plus
50 ms (58 ms): the time from sending the fault on the twin's control port to ur_rtde's receive interface (or the
gripper client) showing it.

The ur_rtde client is built on a thread with real-time scheduling, so its receive thread inherits it, as ur_rtde
arranges itself on a real-time kernel (``RTDEUtility::setRealtimePriority`` on the constructing thread): on this
shared machine a normal-priority reader's wake-ups alone jitter by tens of milliseconds."""

from __future__ import annotations

import contextlib
import os
import socket
import time
from collections.abc import Callable, Iterator

import pytest

from tests.twin.conftest import STRICT_TIMING, TwinProcess
from tests.twin.robotiq_cpp_replica import RobotiqReplica

pytestmark = [pytest.mark.sim, pytest.mark.real_client]
rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")
dashboard_client = pytest.importorskip("dashboard_client")

#: issue 40's bound (asserted with BT_GRASP_STRICT_TIMING=1), and the issue's bound for tests on a loaded machine
STRICT_BOUND_S = 0.008 + 0.050
BOUND_S = STRICT_BOUND_S if STRICT_TIMING else 1.0
TRIALS = 3


@contextlib.contextmanager
def realtime() -> Iterator[bool]:
    """This thread at SCHED_FIFO 5 while inside: above every normal process, below the twin's threads (10, 9),
    so a client never starves the twin it measures."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(5))
    except (OSError, AttributeError):
        yield False
        return
    try:
        yield True
    finally:
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))


@pytest.fixture(scope="module")
def clients(twin: TwinProcess) -> Iterator[tuple[rtde_control.RTDEControlInterface, rtde_receive.RTDEReceiveInterface,
                                                 dashboard_client.DashboardClient]]:
    with realtime():  # the receive threads ur_rtde starts now inherit the scheduling
        c = rtde_control.RTDEControlInterface(twin.host)
        r = rtde_receive.RTDEReceiveInterface(twin.host)
    d = dashboard_client.DashboardClient(twin.host)
    d.connect()
    yield c, r, d
    for closing in (c.disconnect, r.disconnect, d.disconnect):
        with contextlib.suppress(RuntimeError):
            closing()


def latency(twin: TwinProcess, fault: str, seen: Callable[[], bool], timeout_s: float = 1.0) -> float:
    """Seconds from sending ``fault`` to ``seen()`` (polled on a real-time thread)."""
    with socket.create_connection((twin.host, 30100), timeout=5) as s, realtime():
        start = time.perf_counter()
        s.sendall(f"fault {fault}\n".encode())
        while not seen():
            if time.perf_counter() - start > timeout_s:
                raise AssertionError(f"fault {fault} not seen within {timeout_s} s")
            time.sleep(0.0001)  # yield the core (a real-time thread that spins could starve the others)
        took = time.perf_counter() - start
        assert b'"ok": true' in s.recv(4096)
    return took


def back_to_running(c, r, d) -> None:  # type: ignore[no-untyped-def]
    if r.isProtectiveStopped():
        time.sleep(0.5)  # the twin's --unlock-delay
        d.unlockProtectiveStop()
    if not c.isProgramRunning():
        assert c.reuploadScript()
        start = time.perf_counter()
        while not c.isProgramRunning():
            assert time.perf_counter() - start < 2.0
            time.sleep(0.001)


def test_a_protective_stop_is_seen_within_a_period_and_50_ms(twin, clients) -> None:  # type: ignore[no-untyped-def]
    c, r, d = clients
    back_to_running(c, r, d)
    took = []
    for _ in range(TRIALS):
        took.append(latency(twin, "protective-stop", r.isProtectiveStopped))
        assert r.getSafetyMode() == 3 and r.getRuntimeState() == 4
        back_to_running(c, r, d)
    print("protective stop seen after (ms):", [round(t * 1000, 1) for t in took])
    assert max(took) < BOUND_S


def test_a_program_stopped_from_the_pendant_is_seen_within_a_period_and_50_ms(twin, clients) -> None:  # type: ignore[no-untyped-def]
    c, r, d = clients
    back_to_running(c, r, d)
    took = []
    for _ in range(TRIALS):
        took.append(latency(twin, "pendant-stop", lambda: r.getRuntimeState() == 1))
        assert r.getRobotStatus() & 0b10 == 0  # "program running" cleared
        assert r.getRobotMode() == 7  # the robot itself still runs
        back_to_running(c, r, d)
    print("pendant stop seen after (ms):", [round(t * 1000, 1) for t in took])
    assert max(took) < BOUND_S


def test_a_gripper_that_stops_answering_is_seen_by_its_client(twin) -> None:  # type: ignore[no-untyped-def]
    gripper = RobotiqReplica(twin.host, timeout_s=STRICT_BOUND_S)  # the client gives up after 58 ms of silence
    try:
        assert gripper.get_var("FLT") == 0
        assert twin.control("fault gripper-silent")["ok"]
        start = time.perf_counter()
        with pytest.raises(TimeoutError):  # socket.timeout: no answer within the bound
            gripper.get_var("STA")
        # seen by its own timeout; how late the client's thread wakes for it is the machine's load (75 ms measured)
        assert time.perf_counter() - start < (STRICT_BOUND_S + 0.01 if STRICT_TIMING else BOUND_S)
        assert twin.control("fault gripper-answers")["ok"]
        assert gripper.get_var("FLT") == 0  # answers again (the unanswered request stays unanswered)
    finally:
        gripper.close()


def test_a_dropped_connection_is_seen_within_a_period_and_50_ms(twin) -> None:  # type: ignore[no-untyped-def]
    took = []
    for _ in range(TRIALS):
        with realtime():
            r = rtde_receive.RTDEReceiveInterface(twin.host)
        try:
            assert r.isConnected() and r.getTimestamp() > 0
            took.append(latency(twin, "drop-connections 0.2", lambda: not r.isConnected()))  # noqa: B023
        finally:
            with contextlib.suppress(RuntimeError):
                r.disconnect()
        time.sleep(0.25)  # new connections are refused for 0.2 s
    print("dropped connection seen after (ms):", [round(t * 1000, 1) for t in took])
    assert max(took) < BOUND_S
    assert "fault: dropped" in twin.log()
