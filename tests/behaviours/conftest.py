"""The behaviour tests use the perception tests' synthetic RGB-D frames (no simulator)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "perception"))
