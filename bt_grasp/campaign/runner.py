"""Running a campaign: what is left to do, handing it to an engine, writing each row as it arrives.

Engines (:mod:`bt_grasp.campaign.local`, :mod:`bt_grasp.campaign.ray_engine`) only run episodes and yield
what comes back; this module alone reads and writes the results file, so no row is ever written twice.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from bt_grasp.campaign.out_lock import campaign_lock
from bt_grasp.campaign.results import ResultsWriter, read_rows, results_path
from bt_grasp.campaign.rows import ResultRow
from bt_grasp.campaign.spec import Campaign, PlannedEpisode
from bt_grasp.errors import BtGraspError, InputError
from bt_grasp.files.json_types import JsonObject
from bt_grasp.files.output_files import check_output_file

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class EpisodeError:
    """An episode that raised instead of finishing (a bug, or its worker died): no row; it runs again on resume."""

    episode: PlannedEpisode
    message: str
    worker_lost: bool = False


class Engine(Protocol):
    """Runs episodes somewhere and yields each finished row (or error) as soon as it is available."""

    def run(self, episodes: Sequence[PlannedEpisode]) -> Iterator[ResultRow | EpisodeError]: ...


class CampaignIncomplete(BtGraspError):
    """Some episodes did not finish (a worker or node was lost, or an episode raised): resume to finish."""

    exit_code = 3


@dataclass
class Progress:
    total: int  # episodes in the campaign
    already: int  # finished before this run started (resumed)
    done: int = 0  # finished in this run
    successes: int = 0  # over every finished row (resumed ones too)
    finished: int = 0  # rows over which ``successes`` counts
    errors: list[EpisodeError] = field(default_factory=list)
    started_s: float = field(default_factory=time.monotonic)

    @property
    def remaining(self) -> int:
        return self.total - self.already - self.done

    @property
    def rate_per_min(self) -> float:
        elapsed = time.monotonic() - self.started_s
        return 60.0 * self.done / elapsed if elapsed > 0 and self.done else 0.0

    @property
    def eta_s(self) -> float | None:
        rate = self.rate_per_min
        return 60.0 * self.remaining / rate if rate > 0 else None

    @property
    def success_rate(self) -> float | None:
        return self.successes / self.finished if self.finished else None


def pending(campaign: Campaign, rows: list[JsonObject], path: Path) -> list[PlannedEpisode]:
    """The campaign's episodes that have no row yet; rows of episodes not in the campaign are refused."""
    episodes = campaign.episodes()
    keys = {e.key for e in episodes}
    stale = [r for r in rows if r["episode"] not in keys]
    if stale:
        raise InputError(
            path,
            f"holds {len(stale)} row(s) of episodes that are not in {campaign.source} as it is now (an input "
            f"file or the campaign changed, e.g. episode {stale[0].get('tree')} seed {stale[0].get('seed')}); "
            "write to another --out folder",
        )
    done = {r["episode"] for r in rows}
    return [e for e in episodes if e.key not in done]


def run_campaign(
    campaign: Campaign,
    out_dir: Path,
    engine_factory: Callable[[], Engine],
    on_progress: Callable[[Progress, ResultRow | EpisodeError | None], None] | None = None,
) -> Progress:
    """Run every episode of ``campaign`` that has no row in ``out_dir`` yet; rows are on disk as they finish.

    Raises :class:`CampaignIncomplete` when some episodes did not finish (after writing every row that did).
    """
    with campaign_lock(Path(out_dir)):
        return _run_locked(campaign, Path(out_dir), engine_factory, on_progress)


def _run_locked(
    campaign: Campaign,
    out_dir: Path,
    engine_factory: Callable[[], Engine],
    on_progress: Callable[[Progress, ResultRow | EpisodeError | None], None] | None,
) -> Progress:
    path = check_output_file(results_path(out_dir, campaign.name), "--out")  # not a link, device or folder
    rows = read_rows(path, repair=True) if path.exists() else []
    todo = pending(campaign, rows, path)
    progress = Progress(total=len(campaign.episodes()), already=len(rows))
    progress.successes = sum(1 for r in rows if r.get("success"))
    progress.finished = len(rows)
    written = {r["episode"] for r in rows}
    if on_progress is not None:
        on_progress(progress, None)
    if not todo:
        return progress
    with ResultsWriter(path) as writer:
        for item in engine_factory().run(todo):
            if isinstance(item, EpisodeError):
                progress.errors.append(item)
            elif item["episode"] in written:  # never twice, whatever an engine re-delivers
                log.warning("episode %s delivered twice; kept the first row", item["episode"])
                continue
            else:
                writer.append(item)
                written.add(item["episode"])
                progress.done += 1
                progress.finished += 1
                progress.successes += bool(item["success"])
            if on_progress is not None:
                on_progress(progress, item)
    if progress.errors:
        lost = sum(e.worker_lost for e in progress.errors)
        first = progress.errors[0]
        raise CampaignIncomplete(
            f"{len(progress.errors)} episode(s) did not finish ({lost} with a lost worker; first: "
            f"{first.episode.label()}: {first.message}); {progress.already + progress.done} of {progress.total} "
            f"rows are in {path}: run the same command again to resume"
        )
    return progress
