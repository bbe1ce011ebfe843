"""Live streaming of a run to Foxglove over the Foxglove WebSocket protocol (the maintained ``foxglove-sdk``).

A :class:`LiveServer` advertises every topic of a :class:`~bt_grasp.recording.writer.RunRecorder` with the
same schemas as the MCAP file and forwards each message the recorder writes (a recorder "tap"), so a viewer
sees the same topics live as it would in the log. It binds to 127.0.0.1 unless told otherwise.

Never stalls the run: ``Channel.log`` only queues; the SDK keeps at most ``backlog`` outgoing messages per
client and drops the oldest data message when a slow viewer's queue is full (frames are dropped, ticks are
not). A topic written once (the robot model, the fixtures, the tree, the camera calibration) is sent again to
a viewer that subscribes later, so joining mid-run still shows the arm.

Control (``serve_control``): the server always offers the protocol's parameters and client publishing; a run
started with ``--control`` hands them to a :class:`bt_grasp.foxglove.control.FoxgloveControl` (Studio's
Parameters and Publish panels drive the run), any other run answers a client that tries with one sentence.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Mapping
from types import ModuleType
from typing import TYPE_CHECKING

from bt_grasp.errors import BtGraspError, InputError
from bt_grasp.foxglove.layout import COMMAND_TOPIC
from bt_grasp.recording import topics
from bt_grasp.recording.writer import RunRecorder

if TYPE_CHECKING:  # the SDK is imported when a server starts (start-up time of every other run)
    from foxglove import Channel
    from foxglove.websocket import (
        ChannelView,
        Client,
        ClientChannel,
        Parameter,
        PlaybackControlRequest,
        PlaybackState,
        WebSocketServer,
    )

    from bt_grasp.foxglove.control import Answer, FoxgloveControl, ParamValue

log = logging.getLogger(__name__)

DEFAULT_PORT = 8765
#: topics written once or rarely whose last message a late viewer needs
LATCHED: tuple[str, ...] = (topics.ROBOT_MODEL, topics.SCENE, topics.TREE, topics.CALIBRATION,
                            topics.DETECTIONS, topics.GRASPS, topics.POINTS, topics.COLOR)


class LiveServerError(BtGraspError):
    exit_code = 2


#: the status id of control answers (a new answer replaces the last one in a viewer)
CONTROL_STATUS = "bt_grasp.control"
NO_CONTROL = "this run takes no commands: start it with --live --control to drive it from Foxglove"


class _Listener:  # a foxglove.websocket.ServerListener (every callback: the SDK calls them by name)
    """Re-sends the latched topics' last message when a viewer subscribes; parameters and client messages go to
    the run's control (when it has one)."""

    def __init__(self, server: LiveServer) -> None:
        self._server = server
        self._command_channels: set[tuple[int, int]] = set()  # (client, client channel) on the command topic

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        self._server.subscribed(+1)
        self._server.resend(str(channel.topic))

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        self._server.subscribed(-1)

    def on_client_advertise(self, client: Client, channel: ClientChannel) -> None:
        if str(channel.topic) == COMMAND_TOPIC:
            self._command_channels.add((int(client.id), int(channel.id)))

    def on_client_unadvertise(self, client: Client, client_channel_id: int) -> None:
        self._command_channels.discard((int(client.id), int(client_channel_id)))

    def on_message_data(self, client: Client, client_channel_id: int, data: bytes) -> None:
        if (int(client.id), int(client_channel_id)) not in self._command_channels:
            return
        control = self._server.control
        if control is None:
            self._server.status(NO_CONTROL)
            return
        self._server.answer(control.command_message(bytes(data)))

    def on_get_parameters(self, client: Client, param_names: list[str],
                          request_id: str | None = None) -> list[Parameter]:
        control = self._server.control
        return [] if control is None else self._server.parameters(control.parameters(param_names))

    def on_set_parameters(self, client: Client, parameters: list[Parameter],
                          request_id: str | None = None) -> list[Parameter]:
        control = self._server.control
        if control is None:
            self._server.status(NO_CONTROL)
            return []
        self._server.answer(control.set_parameters({p.name: p.get_value() for p in parameters}))
        # the values as the run stands (a paused run applies a command at once; the rest follow as updates)
        return self._server.parameters(control.parameters())

    def on_parameters_subscribe(self, param_names: list[str]) -> None:
        return None

    def on_parameters_unsubscribe(self, param_names: list[str]) -> None:
        return None

    def on_connection_graph_subscribe(self) -> None:
        return None

    def on_connection_graph_unsubscribe(self) -> None:
        return None

    def on_playback_control_request(self, playback_control_request: PlaybackControlRequest) -> PlaybackState | None:
        return None


class LiveServer:
    """A Foxglove WebSocket server for one run. ``attach(recorder)`` before the first tick; ``close()`` after."""

    def __init__(self, port: int = DEFAULT_PORT, host: str = "127.0.0.1", *, name: str = "bt_grasp",
                 backlog: int = 256) -> None:
        if not 0 <= port <= 65535:
            raise InputError("--live", f"a port is a number from 0 to 65535, got {port}")
        import foxglove
        from foxglove.websocket import Capability

        self._foxglove: ModuleType = foxglove
        self._context = foxglove.Context()
        self._channels: dict[str, Channel] = {}
        self._latched: dict[str, tuple[int, bytes]] = {}
        self._lock = threading.Lock()
        self.dropped_errors = 0
        self._subscriptions = 0
        self.control: FoxgloveControl | None = None
        capabilities = [Capability.Parameters, Capability.ClientPublish]
        try:
            self._server: WebSocketServer = foxglove.start_server(
                name=name, host=host, port=port, context=self._context, capabilities=capabilities,
                server_listener=_Listener(self), supported_encodings=["json", "protobuf"], message_backlog_size=backlog,
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

    def serve_control(self, control: FoxgloveControl) -> None:
        """Let viewers drive the run: parameters and ``/control/command`` messages go to ``control``, and the
        run's view goes back as parameter updates."""
        self.control = control
        control.watch(lambda changed: self._publish_parameters(changed), self.status)
        if control.refusal:
            log.warning("%s", control.refusal)

    def parameters(self, values: Mapping[str, ParamValue]) -> list[Parameter]:
        """Parameter values as the SDK's ``Parameter`` objects (a float stays a float on the wire)."""
        from foxglove.websocket import Parameter, ParameterType

        return [Parameter(name, value=list(value) if isinstance(value, list) else value,  # a list of the SDK's
                          type=ParameterType.Float64 if isinstance(value, float) else None)  # values (copied)
                for name, value in values.items()]

    def _publish_parameters(self, changed: Mapping[str, ParamValue]) -> None:
        try:
            self._server.publish_parameter_values(self.parameters(changed))
        except Exception:  # a viewer's updates must never stop the run
            self.dropped_errors += 1
            log.debug("live: could not publish parameter values", exc_info=True)

    def status(self, sentence: str) -> None:
        """Tell every viewer one sentence (Studio lists it under Problems)."""
        from foxglove.websocket import StatusLevel

        try:
            self._server.publish_status(sentence, StatusLevel.Warning, CONTROL_STATUS)
        except Exception:
            self.dropped_errors += 1
            log.debug("live: could not send a status", exc_info=True)

    def answer(self, answer: Answer) -> None:
        for problem in answer.problems:
            self.status(problem)

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
