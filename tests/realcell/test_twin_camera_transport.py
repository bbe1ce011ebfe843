"""The twin's camera transport is a socket: everything read is bounded and checked before use, and anything that
is not the protocol is one sentence (the path through pyrealsense2 itself is driven against a real twin in
tests/realcell/test_cell_on_twin.py)."""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from bt_grasp.hardware.twin_camera import MAX_HEADER_BYTES, TwinCameraError, TwinCameraLink, parse_streams

INTRINSICS = {"width_px": 640, "height_px": 480, "fx_px": 625.2, "fy_px": 625.2, "cx_px": 319.5, "cy_px": 239.5}
STREAMS: dict[str, Any] = {
    "ok": True, "color": INTRINSICS, "depth": {**INTRINSICS, "fx_px": 383.0, "fy_px": 383.0},
    "T_color_depth": [[1, 0, 0, 0.015], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "depth_unit_m": 0.001,
    "fps": 30, "serial": "000000000436", "mount": "eye-to-hand",
}


def test_a_twins_stream_description_becomes_the_software_devices_streams() -> None:
    streams, mount = parse_streams(STREAMS)
    assert streams.color.fx_px == 625.2 and streams.depth.fx_px == 383.0 and streams.T_color_depth[0, 3] == 0.015
    assert mount.value == "eye-to-hand" and streams.fps == 30


@pytest.mark.parametrize(("change", "says"), [
    ({"extra": 1}, "with the keys"),
    ({"color": {**INTRINSICS, "width_px": 100000}}, "a size of 100000"),
    ({"depth": {**INTRINSICS, "fx_px": float("nan")}}, "not finite numbers"),
    ({"depth": {**INTRINSICS, "fx_px": -1.0}}, "not positive"),
    ({"T_color_depth": [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}, "not a rigid transform"),
    ({"T_color_depth": "eye"}, "not a finite 4x4 matrix"),
    ({"depth_unit_m": 5.0}, "a depth unit of 5.0"),
    ({"serial": "../../etc"}, "serial number"),
    ({"mount": "ceiling"}, "a mount of 'ceiling'"),
])
def test_a_malformed_stream_description_is_one_sentence(change: dict[str, Any], says: str) -> None:
    with pytest.raises(TwinCameraError, match=says) as caught:
        parse_streams({**STREAMS, **change})
    assert "\n" not in str(caught.value)


@pytest.fixture
def port() -> Iterator[Callable[[bytes], tuple[str, int]]]:
    servers: list[socket.socket] = []

    def serve(reply: bytes) -> tuple[str, int]:
        server = socket.socket()
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        servers.append(server)

        def answer() -> None:
            try:
                conn, _ = server.accept()
                with conn:
                    conn.recv(64)
                    conn.sendall(reply)
                    conn.recv(64)  # until the client lets go
            except OSError:
                return

        threading.Thread(target=answer, daemon=True).start()
        host, number = server.getsockname()
        return str(host), int(number)

    yield serve
    for server in servers:
        server.close()


@pytest.mark.parametrize(("reply", "says"), [
    (b"x" * (MAX_HEADER_BYTES + 10), "without a line end"),
    (b"[1, 2]\n", "not a JSON object with ok"),
    (b'{"ok": NaN}\n', "not a JSON object"),
    (b"\xff\xfe\n", "not a JSON object"),
])
def test_hostile_replies_are_refused_with_one_sentence(port, reply: bytes, says: str) -> None:  # type: ignore[no-untyped-def]
    host, number = port(reply)
    link = TwinCameraLink(host, number, timeout_s=2.0)
    try:
        with pytest.raises(TwinCameraError, match=says):
            link.request("streams")
    finally:
        link.close()


def test_a_port_that_answers_nothing_times_out_within_its_bound(port) -> None:  # type: ignore[no-untyped-def]
    host, number = port(b"")
    link = TwinCameraLink(host, number, timeout_s=0.3)
    try:
        with pytest.raises(TimeoutError, match=r"sent nothing for 0\.3 s"):
            link.request("frame")
    finally:
        link.close()


def test_nothing_listening_is_one_sentence() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        number = probe.getsockname()[1]
    with pytest.raises(TwinCameraError, match=r"cannot be reached .* `bt-grasp twin` running there"):
        TwinCameraLink("127.0.0.1", number)
