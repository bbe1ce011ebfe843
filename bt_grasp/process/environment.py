"""What machine and libraries a run or a benchmark ran on: the one place these strings are made."""

from __future__ import annotations

import os
import platform
from functools import cache
from importlib.metadata import PackageNotFoundError, version

#: the libraries whose versions decide a run's numbers (recorded in every log)
KEY_LIBRARIES = ("bt-grasp", "sapien", "py-trees", "opencv-python-headless", "open3d", "pin", "ompl", "ruckig", "mcap")


@cache  # installed versions do not change under a running process; looking one up reads package metadata
def library_version(name: str) -> str:
    try:
        return version(name)
    except PackageNotFoundError:
        return "?"


def versions_line() -> str:
    """``bt-grasp=0.1.0 sapien=3.0.0 ...`` for the key libraries."""
    return " ".join(f"{name}={library_version(name)}" for name in KEY_LIBRARIES)


def cpu_model() -> str:
    """The CPU's model name (from /proc/cpuinfo on Linux), else what ``platform`` knows."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine_description() -> str:
    """``x86_64, 2 cores, Python 3.11.2``: what benchmark figures are quoted with."""
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
