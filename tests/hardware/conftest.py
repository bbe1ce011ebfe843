"""tests/hardware: pyrealsense2 itself (the realsense extra, installed with dev); skipped with the reason where it is
missing (a machine without the extra), never stood in for."""

from __future__ import annotations

import pytest

pytest.importorskip("pyrealsense2", reason="the realsense extra is not installed (pip install -e '.[realsense]')")
