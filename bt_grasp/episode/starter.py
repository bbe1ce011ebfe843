"""A starter project in a folder of one's own (``bt-grasp init DIR``): a task tree, its scene, the camera's
calibration and a campaign, which run as written from any folder once bt_grasp is installed.

The files are bt_grasp's package data (``bt_grasp/assets/starter``, the calibration
``bt_grasp/assets/calibrations/tabletop.calibration.yaml``), so an installed bt_grasp writes exactly what the
checkout's tests ran (``tests/test_init_from_an_installed_wheel.py``). The tree includes the shipped library
subtrees (``lib/pick.xml``, ``lib/place.xml``), found in bt_grasp's own files (``bt_grasp/files/search_path.py``).
"""

from __future__ import annotations

from pathlib import Path

from bt_grasp.errors import InputError
from bt_grasp.files.output_files import check_output_folder, make_output_folder, write_output_file
from bt_grasp.files.search_path import ASSETS, SHIPPED_CALIBRATIONS

STARTER = ASSETS / "starter"
#: what ``bt-grasp init`` writes, in this order, and what each file is
STARTER_FILES: dict[str, str] = {
    "task.xml": "the task's behaviour tree",
    "scene.yaml": "the scene and the goal the judge checks",
    "calibration.yaml": "the camera's hand-eye calibration, which the scene names",
    "campaign.yaml": "an evaluation of the task over seeds, with and without a fault",
}


def starter_bytes(name: str) -> bytes:
    """The bytes ``bt-grasp init`` writes as ``name`` (one of :data:`STARTER_FILES`)."""
    if name == "calibration.yaml":
        return (SHIPPED_CALIBRATIONS / "tabletop.calibration.yaml").read_bytes()
    return (STARTER / name).read_bytes()


def write_starter(folder: Path, *, force: bool = False) -> list[Path]:
    """Write the starter project into ``folder`` (made if missing) and return the files written. A file of the
    project already there is kept and nothing is written (:class:`InputError`, exit 2) unless ``force``."""
    check_output_folder(folder, "DIR")
    existing = [folder / name for name in STARTER_FILES if (folder / name).exists()]
    if existing and not force:
        names = ", ".join(p.name for p in existing)
        raise InputError("DIR", f"'{folder}' already holds {names}; nothing was written (another folder, or "
                                "--force to overwrite them)")
    make_output_folder(folder, "DIR")
    return [write_output_file(folder / name, starter_bytes(name), "DIR") for name in STARTER_FILES]
