"""The twin's TCP plumbing: one thread with a selector serves every port; peers are treated as hostile.

Each port has a :class:`Protocol` object that makes one :class:`Session` per accepted connection. The loop reads
at most :data:`READ_CHUNK` bytes at a time and hands them to the session; a session keeps its own bounded
buffer and raises :class:`Refused` (one sentence) for anything it will not take, and the loop logs the sentence
and closes the connection. A message begun but not finished within the port's ``message_timeout_s`` is refused
the same way (a per-connection timeout); a peer that stops reading is dropped when a reply does not fit in its
socket buffer (as a UR controller closes an RTDE client whose buffer overflows).

:meth:`Link.send` may be called from any thread (the controller thread sends RTDE data packages directly, so a
package leaves at the controller's period and never waits for this loop).
"""

from __future__ import annotations

import contextlib
import logging
import selectors
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from bt_grasp.sim.twin.realtime import ask_for_realtime

log = logging.getLogger(__name__)

READ_CHUNK = 65536
#: how often the loop checks message timeouts when nothing arrives
POLL_S = 0.05


class Refused(Exception):
    """A peer sent something the twin will not take; the text is one sentence and the connection closes."""


class Session:
    """One connection's protocol state. Subclasses override the hooks; the loop calls them on its thread."""

    def __init__(self, link: Link) -> None:
        self.link = link

    def on_open(self) -> None:
        """Called once after the connection is accepted (send a greeting here)."""

    def on_bytes(self, data: bytes) -> None:
        """Bytes arrived (at most :data:`READ_CHUNK`). Raise :class:`Refused` to close the connection."""

    def on_close(self) -> None:
        """Called once when the connection closed, whoever closed it."""

    def partial_since(self) -> float | None:
        """The monotonic time a message began that has not been completed, or None."""
        return None


class Link:
    """One accepted connection: ``send`` from any thread (whole or the connection closes), ``close`` likewise."""

    def __init__(self, sock: socket.socket, peer: str, port_name: str) -> None:
        self.sock = sock
        self.peer = peer
        self.port_name = port_name
        self._lock = threading.Lock()
        self.closed = False
        self.session: Session | None = None

    def send(self, data: bytes) -> bool:
        """Queue ``data`` in the socket's buffer without waiting. A peer that does not read (the buffer is full)
        is dropped with one logged sentence; returns False then, or when the link is closed."""
        with self._lock:
            if self.closed:
                return False
            try:
                sent = self.sock.send(data)
            except BlockingIOError:
                sent = 0
            except OSError as exc:
                self._close_locked(f"sending failed ({exc.strerror or exc})")
                return False
            if sent != len(data):
                self._close_locked("the peer does not read what the twin sends (its buffer is full); dropped")
                return False
            return True

    def close(self, reason: str | None = None) -> None:
        """Close the connection; ``reason`` (one sentence) is logged."""
        with self._lock:
            self._close_locked(reason)

    def _close_locked(self, reason: str | None) -> None:
        if self.closed:
            return
        self.closed = True
        if reason:
            log.warning("%s connection from %s closed: %s", self.port_name, self.peer, reason)
        with contextlib.suppress(OSError):  # wakes the loop, which unregisters and closes the socket
            self.sock.shutdown(socket.SHUT_RDWR)


def listening_socket(host: str, port: int, name: str, backlog: int) -> socket.socket:
    """A TCP socket listening on host:port (address reuse on: a twin restarted at once binds again); an OSError naming
    the address and the port's use when it is taken."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        raise OSError(exc.errno, f"{host}:{port} ({name}): {exc.strerror}") from exc
    sock.listen(backlog)
    return sock

@dataclass(frozen=True)
class Protocol:
    """A port the twin serves."""

    name: str  # "RTDE", "dashboard", ... (in log sentences)
    port: int
    make_session: Callable[[Link], Session]
    max_connections: int = 8
    message_timeout_s: float = 5.0


class IoLoop:
    """Serves a set of :class:`Protocol` on one host address from one daemon thread."""

    def __init__(self, host: str, protocols: list[Protocol], realtime_priority: int | None = None) -> None:
        """``realtime_priority``: ask for real-time scheduling of the loop's thread (inputs then reach the
        controller within its cycle on a busy machine; see :mod:`bt_grasp.sim.twin.realtime`)."""
        self.host = host
        self.realtime_priority = realtime_priority
        self.protocols = protocols
        self._selector = selectors.DefaultSelector()
        self._listeners: dict[socket.socket, Protocol] = {}
        self._links: dict[socket.socket, Link] = {}
        self._lock = threading.Lock()
        self._refuse_until = 0.0
        self._spared: tuple[str, ...] = ()
        self._stop = threading.Event()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._thread = threading.Thread(target=self._run, name="twin-io", daemon=True)

    def bind(self) -> None:
        """Bind every port (OSError naming the port when one is taken); nothing is served until :meth:`start`."""
        for proto in self.protocols:
            try:
                sock = listening_socket(self.host, proto.port, proto.name, backlog=16)
            except OSError:
                self.close_listeners()
                raise
            sock.setblocking(False)
            self._listeners[sock] = proto

    def start(self) -> None:
        for sock in self._listeners:
            self._selector.register(sock, selectors.EVENT_READ, None)
        self._selector.register(self._wake_r, selectors.EVENT_READ, None)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._wake()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        with self._lock:
            links = list(self._links.values())
        for link in links:
            link.close()
            self._forget(link)
        self.close_listeners()
        with contextlib.suppress(KeyError, ValueError):
            self._selector.unregister(self._wake_r)
        self._selector.close()
        self._wake_r.close()
        self._wake_w.close()

    def close_listeners(self) -> None:
        for sock in list(self._listeners):
            with contextlib.suppress(KeyError, ValueError):
                self._selector.unregister(sock)
            sock.close()
        self._listeners.clear()

    def links(self, port_name: str | None = None) -> list[Link]:
        with self._lock:
            return [lk for lk in self._links.values() if port_name is None or lk.port_name == port_name]

    def drop_all(self, refuse_for_s: float, spare: tuple[str, ...] = ()) -> int:
        """The "dropped connection" fault: close every connection, and close new ones at once for ``refuse_for_s``
        (as if the cable were out), except on the ports named in ``spare``. Returns how many were closed."""
        self._spared = spare
        self._refuse_until = time.monotonic() + max(0.0, refuse_for_s)
        links = [link for link in self.links() if link.port_name not in spare]
        for link in links:
            link.close(None)
        log.warning("fault: dropped %d connections; new ones are refused for %.1f s", len(links), refuse_for_s)
        return len(links)

    def _wake(self) -> None:
        with contextlib.suppress(OSError):
            self._wake_w.send(b"x")

    def _run(self) -> None:
        ask_for_realtime(self.realtime_priority, "the twin's network thread")
        while not self._stop.is_set():
            try:
                events = self._selector.select(POLL_S)
            except OSError:  # a socket closed under the selector: tidy up below
                events = []
            for key, _ in events:
                sock = key.fileobj
                assert isinstance(sock, socket.socket)
                if sock is self._wake_r:
                    try:
                        while self._wake_r.recv(4096):
                            pass
                    except BlockingIOError:
                        pass
                elif sock in self._listeners:
                    self._accept(sock, self._listeners[sock])
                else:
                    link = self._links.get(sock)
                    if link is not None:
                        self._read(link)
            self._check_timeouts()

    def _accept(self, listener: socket.socket, proto: Protocol) -> None:
        try:
            sock, addr = listener.accept()
        except (BlockingIOError, OSError):
            return
        peer = f"{addr[0]}:{addr[1]}"
        # the wall clock on purpose: the twin is a real-time controller for real-time clients (ur_rtde), as a robot
        # is; no simulated run reads it, and a real-cell run against a twin is a wall-clock run whose log says so
        if time.monotonic() < self._refuse_until and proto.name not in self._spared:
            sock.close()  # the "dropped connection" fault is still on
            return
        if len(self.links(proto.name)) >= proto.max_connections:
            log.warning("%s connection from %s refused: %d connections are open already (the twin's limit)",
                        proto.name, peer, proto.max_connections)
            sock.close()
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        link = Link(sock, peer, proto.name)
        link.session = proto.make_session(link)
        with self._lock:
            self._links[sock] = link
        self._selector.register(sock, selectors.EVENT_READ, None)
        log.info("%s connection from %s", proto.name, peer)
        try:
            link.session.on_open()
        except Refused as exc:
            link.close(str(exc))

    def _read(self, link: Link) -> None:
        try:
            data = link.sock.recv(READ_CHUNK)
        except BlockingIOError:
            return
        except OSError:
            data = b""
        if not data or link.closed:
            if not link.closed:
                log.info("%s connection from %s closed by the peer", link.port_name, link.peer)
            link.close(None)
            self._forget(link)
            return
        assert link.session is not None
        try:
            link.session.on_bytes(data)
        except Refused as exc:
            link.close(str(exc))
            self._forget(link)

    def _forget(self, link: Link) -> None:
        with self._lock:
            known = self._links.pop(link.sock, None)
        if known is None:
            return
        with contextlib.suppress(KeyError, ValueError):
            self._selector.unregister(link.sock)
        link.sock.close()
        if link.session is not None:
            link.session.on_close()

    def _check_timeouts(self) -> None:
        now = time.monotonic()
        timeouts = {p.name: p.message_timeout_s for p in self.protocols}
        for link in self.links():
            if link.closed:
                self._forget(link)
                continue
            since = link.session.partial_since() if link.session is not None else None
            limit = timeouts.get(link.port_name, 5.0)
            if since is not None and now - since > limit:
                link.close(f"a message begun {now - since:.1f} s ago was not finished (the twin waits {limit:g} s)")
                self._forget(link)
