"""What a camera SOURCE names: a recording file, a live device (by serial number, or the only one), or a scene."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.errors import InputError
from bt_grasp.interfaces import Mount


class SourceKind(enum.Enum):
    RECORDING = "recording"
    DEVICE = "device"
    SCENE = "scene"


@dataclass(frozen=True)
class SourceSpec:
    """``path``: the recording; ``serial``: the device ('' = the only one connected); ``scene``/``seed``/``mount``:
    the simulated cell (``mount`` None = the scene's own)."""

    kind: SourceKind
    path: Path | None = None
    serial: str = ""
    scene: Path | None = None
    seed: int = 0
    mount: Mount | None = None

    def describe(self) -> str:
        if self.kind is SourceKind.RECORDING:
            return f"recording {self.path}"
        if self.kind is SourceKind.DEVICE:
            return f"RealSense device {self.serial}" if self.serial else "the RealSense device connected"
        mount = f", {self.mount.value}" if self.mount else ""
        return f"scene {self.scene} seed {self.seed}{mount} (simulated D435 through pyrealsense2)"

    @classmethod
    def recording(cls, path: str | Path) -> SourceSpec:
        return cls(SourceKind.RECORDING, path=Path(path))

    @classmethod
    def device(cls, serial: str = "") -> SourceSpec:
        return cls(SourceKind.DEVICE, serial=serial.strip())

    @classmethod
    def simulated(cls, scene: str | Path, seed: int, mount: Mount | None = None) -> SourceSpec:
        return cls(SourceKind.SCENE, scene=Path(scene), seed=seed, mount=mount)


def choose_source(recording: Path | None, device: str | None, scene: Path | None, seed: int,
                  mount: Mount | None = None) -> SourceSpec:
    """Exactly one of a recording, ``--device [SERIAL]`` (``device`` '' = the only one) or ``--scene``;
    InputError (one sentence) otherwise."""
    given = [name for name, value in (("a recording", recording), ("--device", device), ("--scene", scene))
             if value is not None]
    if len(given) != 1:
        problem = "nothing was given" if not given else f"{' and '.join(given)} were given"
        raise InputError("SOURCE", f"give one source: a recording file, --device [SERIAL] or --scene SCENE "
                         f"--seed N ({problem})")
    if recording is not None:
        return SourceSpec.recording(recording)
    if device is not None:
        return SourceSpec.device(device)
    assert scene is not None
    return SourceSpec.simulated(scene, seed, mount)


def parse_camera_option(text: str) -> SourceSpec:
    """``tree run --camera``: a recording file, or ``device`` / ``device:SERIAL`` for a live one."""
    if text == "device" or text.startswith("device:"):
        return SourceSpec.device(text.partition(":")[2])
    return SourceSpec.recording(text)
