"""Episodes on a Ray cluster: one actor per worker slot, each holding a warm :class:`Worker`.

Ray does the scheduling, placement and fault tolerance (actors restart on a lost node, their method calls
are retried); this module only hands each idle actor the next episode and yields rows as they come back.
Every node needs bt_grasp installed at the same version and the campaign's input files at the same paths
(a shared folder or the same checkout): see docs/campaigns.md.

The actors die with the driver (the coordinator): they are created ``non_detached`` explicitly (not left to a
job config's ``default_actor_lifetime``), so Ray's GCS kills them when the driver's job ends, however the driver
ends (a SIGKILLed driver's job ends when its connection drops). A local cluster that ``ray.init`` starts
(``--ray local``) fate-shares with the driver too: Ray starts its processes with ``PR_SET_PDEATHSIG`` on Linux (a
reaper process elsewhere). Measured (2 cores, Ray 2.60, the driver SIGKILLed mid-campaign): with ``--ray local``
the raylet and GCS went at once, the actors within 3 s, Ray's dashboard and runtime-env agents after ~63 s; on a
cluster the actors went and the cluster stayed (``tests/campaign/test_worker_lifetime.py``).
"""

from __future__ import annotations

import logging
import socket
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

from bt_grasp.campaign.episode import EpisodeBackend
from bt_grasp.campaign.rows import ResultRow
from bt_grasp.campaign.runner import EpisodeError
from bt_grasp.campaign.spec import PlannedEpisode
from bt_grasp.campaign.worker import WORKER_ENV, KeepLogs, Worker
from bt_grasp.errors import InputError

if TYPE_CHECKING:  # Ray is imported when a campaign connects to it (it is an optional extra)
    from ray import ObjectRef
    from ray.actor import ActorHandle

log = logging.getLogger(__name__)

#: the options of every episode actor: one CPU each, restarted on a lost node, and never detached (an actor
#: outliving its driver would hold ~700 MB and a CPU slot with nobody to hand it episodes)
ACTOR_OPTIONS: dict[str, int | str] = {"num_cpus": 1, "max_restarts": 2, "max_task_retries": 2,
                                       "lifetime": "non_detached"}


class EpisodeActor:
    """A Ray actor around one warm worker (its simulator and renderer stay up between episodes)."""

    def __init__(self, factory: Callable[[], EpisodeBackend], log_dir: Path, keep_logs: KeepLogs) -> None:
        logging.getLogger().addHandler(logging.NullHandler())
        Path(log_dir).mkdir(parents=True, exist_ok=True)
        self.worker = Worker(factory, log_dir, keep_logs)

    def run(self, episode: PlannedEpisode) -> ResultRow:
        return self.worker.run(episode)


#: how long the head's address may take to accept a TCP connection before the campaign gives up on it
PROBE_TIMEOUT_S = 3.0


def probe_address(address: str, timeout: float = PROBE_TIMEOUT_S) -> None:
    """Refuse, within ``timeout`` seconds and in one sentence, a ``--ray HOST:PORT`` nobody answers on.

    ``ray.init`` on an unreachable address retries for about two minutes while Ray's C++ core prints its own
    warnings; a plain TCP connection to the head's GCS port answers the same question at once. ``local``,
    ``auto`` and ``ray://`` client addresses are left to Ray (they fail fast, or are not a GCS port)."""
    if address in ("local", "auto") or "://" in address:
        return
    host, sep, port_text = address.rpartition(":")
    if not sep or not host or not port_text.isdigit() or not 0 < int(port_text) < 65536:
        raise InputError("--ray", f"expected HOST:PORT (the head's GCS port, 6379 by default), 'auto' or 'local', "
                                  f"got '{address}'")
    try:
        with socket.create_connection((host.strip("[]"), int(port_text)), timeout=timeout):
            pass
    except OSError as exc:
        reason = "no answer" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc)).lower()
        raise InputError(
            "--ray", f"cannot reach the Ray cluster at '{address}' ({reason} within {timeout:g} s); is "
            "`ray start --head` running there, and the port open?"
        ) from None


class RayEngine:
    def __init__(
        self,
        address: str,
        workers: int | None,
        backend_factory: Callable[[], EpisodeBackend],
        log_dir: Path,
        keep_logs: KeepLogs,
    ) -> None:
        self.address = address
        self.workers = workers
        self.backend_factory = backend_factory
        self.log_dir = log_dir
        self.keep_logs = keep_logs

    def _connect(self) -> ModuleType:
        probe_address(self.address)
        import ray

        address = None if self.address == "local" else self.address
        try:
            ray.init(
                address=address,
                include_dashboard=False,
                log_to_driver=False,
                logging_level=logging.WARNING,
                configure_logging=False,
            )
        except (ConnectionError, RuntimeError, ValueError) as exc:
            raise InputError("--ray", f"cannot connect to the Ray cluster at '{self.address}': {exc}") from None
        return ray

    def run(self, episodes: Sequence[PlannedEpisode]) -> Iterator[ResultRow | EpisodeError]:
        ray = self._connect()
        try:
            slots = self.workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
            actor_cls = ray.remote(**ACTOR_OPTIONS, runtime_env={"env_vars": dict(WORKER_ENV)})(EpisodeActor)
            actors = [
                actor_cls.remote(self.backend_factory, self.log_dir, self.keep_logs)
                for _ in range(min(slots, len(episodes)))
            ]
            queue = list(reversed(episodes))
            running: dict[ObjectRef[ResultRow], tuple[PlannedEpisode, ActorHandle[EpisodeActor]]] = {}
            for actor in actors:
                if queue:
                    episode = queue.pop()
                    running[actor.run.remote(episode)] = (episode, actor)
            while running:
                ready, _ = ray.wait(list(running), num_returns=1)
                episode, actor = running.pop(ready[0])
                try:
                    yield ray.get(ready[0])
                except ray.exceptions.RayActorError as exc:
                    yield EpisodeError(episode, f"worker lost: {exc}".splitlines()[0], worker_lost=True)
                except ray.exceptions.RayTaskError as exc:
                    yield EpisodeError(episode, str(exc).splitlines()[0])
                if queue:
                    nxt = queue.pop()
                    running[actor.run.remote(nxt)] = (nxt, actor)
        finally:
            ray.shutdown()
