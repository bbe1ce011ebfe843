"""The campaign's ``fingerprint`` column: the project's run fingerprint (``bt_grasp.recording.fingerprint``).

Computed from the episode's MCAP log, the same way ``bt-grasp replay --resim`` compares a recorded run with
its re-simulation, so a campaign row and a log can be compared directly. Workers therefore record every
episode; a log the ``--keep-logs`` policy does not keep is deleted once its fingerprint is taken.
"""

from __future__ import annotations

from pathlib import Path


def run_fingerprint(log: Path) -> str:
    from bt_grasp.recording.fingerprint import fingerprint_of_log
    from bt_grasp.recording.reader import open_log

    return fingerprint_of_log(open_log(log)).digest
