"""Live streaming of a run to Foxglove over the Foxglove WebSocket protocol (the maintained ``foxglove-sdk``).

A :class:`LiveServer` advertises every topic of a :class:`~bt_grasp.recording.writer.RunRecorder` with the
same schemas as the MCAP file and forwards each message the recorder writes (a recorder "tap"), so a viewer
sees the same topics live as it would in the log. It binds to 127.0.0.1 unless told otherwise.

Never stalls the run: ``Channel.log`` only queues; the SDK keeps at most ``backlog`` outgoing messages per
client and drops the oldest data message when a slow viewer's queue is full (frames are dropped, ticks are
not). A topic written once (the robot model, the fixtures, the tree, the camera calibration) is sent again to
a viewer that subscribes later, so joining mid-run still shows the arm.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from typing import Any

from bt_grasp.errors import BtGraspError, InputError
from bt_grasp.recording import topics
from bt_grasp.recording.writer import RunRecorder

log = logging.getLogger(__name__)

DEFAULT_PORT = 8765
#: topics written once or rarely whose last message a late viewer needs
LATCHED: tuple[str, ...] = (topics.ROBOT_MODEL, topics.SCENE, topics.TREE, topics.CALIBRATION,
                            topics.DETECTIONS, topics.GRASPS, topics.POINTS, topics.COLOR)


class LiveServerError(BtGraspError):
    exit_code = 2


class _Listener:  # implements foxglove.ServerListener (a Protocol with defaults for the other callbacks)
    """Re-sends the latched topics' last message when a viewer subscribes."""

    def __init__(self, server: LiveServer) -> None:
        self._server = server

    def on_subscribe(self, client: Any, channel: Any) -> None:
        self._server.subscribed(+1)
        self._server.resend(str(channel.topic))

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        self._server.subscribed(-1)


class LiveServer:
    """A Foxglove WebSocket server for one run. ``attach(recorder)`` before the first tick; ``close()`` after."""

    def __init__(self, port: int = DEFAULT_PORT, host: str = "127.0.0.1", *, name: str = "bt_grasp",
                 backlog: int = 256) -> None:
        if not 0 <= port <= 65535:
            raise InputError("--live", f"a port is a number from 0 to 65535, got {port}")
        import foxglove

        self._foxglove = foxglove
        self._context = foxglove.Context()
        self._channels: dict[str, Any] = {}
        self._latched: dict[str, tuple[int, bytes]] = {}
        self._lock = threading.Lock()
        self.dropped_errors = 0
        self._subscriptions = 0
        try:
            self._server = foxglove.start_server(
                name=name, host=host, port=port, context=self._context,
                server_listener=_Listener(self),  # type: ignore[arg-type]
                supported_encodings=["json", "protobuf"], message_backlog_size=backlog,
            )
        except Exception as exc:  # the port is taken, the host cannot be bound, ...
            raise LiveServerError(f"cannot serve a live view on {host}:{port}: {exc}") from exc
        self.host = host
        self.port = int(self._server.port)

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def attach(self, recorder: RunRecorder) -> None:
        """Advertise the recorder's topics and forward everything it writes from now on."""
        fg = self._foxglove
        for spec in recorder.channel_specs():
            schema = fg.Schema(name=spec.schema_name, encoding=spec.schema_encoding, data=spec.schema_data)
            self._channels[spec.topic] = fg.Channel(spec.topic, schema=schema,
                                                    message_encoding=spec.message_encoding, context=self._context)
        recorder.add_tap(self._tap, wanted=lambda: self._subscriptions > 0)

    def subscribed(self, change: int) -> None:
        with self._lock:
            self._subscriptions = max(0, self._subscriptions + change)

    @property
    def watched(self) -> bool:
        """Whether a viewer subscribes to anything now (with nobody watching, the run skips the live work)."""
        return self._subscriptions > 0

    def _tap(self, topic: str, time_ns: int, data: bytes) -> None:
        channel = self._channels.get(topic)
        if channel is None:
            return
        if topic in LATCHED:
            with self._lock:
                self._latched[topic] = (time_ns, data)
        try:
            channel.log(data, log_time=time_ns)
        except Exception:  # a live view must never stop the run
            self.dropped_errors += 1
            log.debug("live: could not forward a message on %s", topic, exc_info=True)

    def resend(self, topic: str) -> None:
        with self._lock:
            last = self._latched.get(topic)
        channel = self._channels.get(topic)
        if last is not None and channel is not None:
            try:
                channel.log(last[1], log_time=last[0])
            except Exception:
                self.dropped_errors += 1

    def close(self) -> None:
        for channel in self._channels.values():
            with contextlib.suppress(Exception):
                channel.close()
        self._server.stop()
