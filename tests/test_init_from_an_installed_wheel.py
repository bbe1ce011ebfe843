"""A newcomer's first hour from an installed bt_grasp, in a folder outside the checkout (issue 43, finding 3).

The one test here builds bt_grasp's wheel from the checkout's files, installs it (no editable install, so a file
missing from the package data is missing here too) into a throwaway virtual environment whose dependencies are
the suite's own, and in an empty folder runs what `bt-grasp init` prints: validate the tree, run the task (judged
by physics), replay its log, run the campaign, write its report. On main, ``bt-grasp init`` did not exist, and a
tree outside the checkout could not include ``lib/pick.xml`` (``trees/`` was not in the package).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PIP = [sys.executable, "-m", "pip"]


def _sources(into: Path) -> None:
    """The files a wheel is built from (pyproject.toml, README.md, bt_grasp/ as git lists it, new files too),
    copied so that the build writes nothing into the checkout."""
    listed = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "pyproject.toml",
                             "README.md", "bt_grasp"], cwd=REPO, capture_output=True, text=True, check=True)
    for name in listed.stdout.split():
        source = REPO / name
        if source.is_file():
            (into / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, into / name)


def _venv_with_the_wheel(tmp: Path) -> Path:
    """A virtual environment holding the wheel alone; the suite's site-packages (the dependencies) come after
    it on the path, its .pth files run (cmeel's adds pinocchio's folder; the editable install's finder is
    appended after the path's, so the wheel's bt_grasp is the one imported: checked by the test)."""
    src, wheels, venv = tmp / "src", tmp / "wheels", tmp / "venv"
    _sources(src)
    done = subprocess.run([*PIP, "wheel", "-q", "--no-deps", "-w", str(wheels), str(src)], capture_output=True,
                          text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    [wheel] = wheels.glob("bt_grasp-*.whl")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    done = subprocess.run([*PIP, "--python", str(venv / "bin/python"), "install", "-q", "--no-deps", "--no-index",
                           str(wheel)], capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    purelib = subprocess.run([str(venv / "bin/python"), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                             capture_output=True, text=True, check=True).stdout.strip()
    Path(purelib, "zz_suite_dependencies.pth").write_text(
        f"import site; site.addsitedir({sysconfig.get_path('purelib')!r})\n")
    return venv


@pytest.mark.sim
@pytest.mark.slow
def test_init_runs_as_written_from_an_installed_wheel(tmp_path: Path) -> None:
    venv = _venv_with_the_wheel(tmp_path / "install")
    home = tmp_path / "newcomer"
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "BT_GRASP_"))}
    env["COLUMNS"] = "200"

    def bt(*args: str, timeout: float = 600) -> subprocess.CompletedProcess[str]:
        return subprocess.run([str(venv / "bin/bt-grasp"), *args], cwd=home, env=env, capture_output=True, text=True,
                              timeout=timeout, check=False)

    where = subprocess.run([str(venv / "bin/python"), "-c", "import bt_grasp; print(bt_grasp.__file__)"], cwd=home,
                           env=env, capture_output=True, text=True, check=True).stdout
    assert where.startswith(str(venv)), where  # the installed copy, not the checkout
    init = bt("init", "my_task")
    assert init.returncode == 0, init.stdout + init.stderr
    commands = [line.split()[1:] for line in init.stdout.splitlines() if line.startswith("  bt-grasp ")]
    expected = [["tree", "validate"], ["run", "my_task/task.xml"], ["replay", "my_task/run.mcap"], ["eval", "run"],
                ["eval", "report"]]
    assert [c[:2] for c in commands] == expected, init.stdout
    for command in commands:  # as printed, one after the other
        done = bt(*command)
        assert done.returncode == 0, f"bt-grasp {' '.join(command)}\n{done.stdout}\n{done.stderr}"
        assert "Traceback" not in done.stderr, done.stderr
        if command[0] == "run":
            assert "SUCCESS" in done.stdout and "goal place judged by physics" in done.stdout, done.stdout
        if command[:2] == ["eval", "run"]:
            assert "4 episodes, 4 succeeded" in done.stdout, done.stdout
    assert (home / "my_task/results/report.html").stat().st_size > 0
