"""The environment fingerprint of a results row: what it was computed with (code, libraries, CPU, Python, OS)."""

from __future__ import annotations

import hashlib
import json
import os
import platform
from functools import lru_cache

from bt_grasp.campaign.rows import Environment
from bt_grasp.process.code_fingerprint import code_fingerprint
from bt_grasp.process.environment import KEY_LIBRARIES, cpu_model, library_version

#: the run's key libraries, plus what changes numbers or speed underneath them
LIBRARIES = (*KEY_LIBRARIES, "numpy", "ray")


@lru_cache(maxsize=1)
def environment() -> Environment:
    env: Environment = {
        "code": code_fingerprint(),  # the package's files and the libraries that change a run (one worker's start)
        "libraries": {name: library_version(name) for name in LIBRARIES},
        "python": platform.python_version(),
        "os": f"{platform.system()} {platform.release()}",
        "machine": platform.machine(),
        "cpu_model": cpu_model(),
        "cpu_count": os.cpu_count(),
        "vulkan_icd": os.environ.get("VK_ICD_FILENAMES", ""),
    }
    env["id"] = hashlib.sha256(json.dumps(env, sort_keys=True).encode()).hexdigest()[:12]
    return env
