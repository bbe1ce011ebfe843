"""TEMPORARY run fingerprint, used only for the campaign's ``fingerprint`` column.

The motion-determinism issue (13) defines the project's one run fingerprint; when it lands on main this
module is replaced by a call to it. Until then: a hash of the per-tick statuses, every failure reason, the
final blackboard, the final joints rounded to 1e-6 rad, the gripper width and the final object poses.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from bt_grasp.campaign.episode import EpisodeOutcome

_ROUND = 6  # 1e-6 rad / m


def _r(values: Any) -> list[float]:
    return [round(float(v), _ROUND) + 0.0 for v in values]


def temporary_run_fingerprint(outcome: EpisodeOutcome) -> str:
    h = hashlib.sha256()
    for tick in outcome.stream:
        h.update(json.dumps(tick, sort_keys=True, default=str).encode())
    payload = {
        "failures": [(f.get("tick"), f.get("leaf"), f.get("reason")) for f in outcome.failures],
        "blackboard": outcome.blackboard,
        "q_rad": _r(outcome.final.q_rad),
        "gripper_width_m": round(outcome.final.gripper_width_m, _ROUND) + 0.0,
        "objects": {k: _r(v) for k, v in sorted(outcome.final.object_poses.items())},
    }
    h.update(json.dumps(payload, sort_keys=True, default=str).encode())
    return h.hexdigest()[:32]
