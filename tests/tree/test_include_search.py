"""Working in one's own folder (issue 43, finding 3): where an include is looked for, what a log carries of it,
and what `replay --resim` reads.

An include is looked for beside the including file, then in each folder of ``BT_GRASP_TREE_PATH``, then in
bt_grasp's shipped library (package data, so an installed bt_grasp has ``lib/pick.xml`` and ``lib/place.xml``);
an absolute include is the user's own choice. A log names every included file's attachment and which include it
answered (run metadata ``tree_includes``), and a re-simulation resolves each include to the log's own copy only.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from bt_grasp.behaviours import robot_registry
from bt_grasp.cli.resim import _recorded_include_links
from bt_grasp.episode.metadata import tree_attachment_names, tree_include_links
from bt_grasp.errors import LogFileError, TreeFileError
from bt_grasp.files.bounded_io import confined_to
from bt_grasp.files.search_path import SHIPPED_TREES, TREE_PATH_VARIABLE
from bt_grasp.tree import builtin_registry, load_tree
from bt_grasp.tree.loader import read_document, recorded_includes

REPO = Path(__file__).resolve().parents[2]


def _lib(folder: Path, tree_id: str, name: str = "lib.xml") -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'<root BTCPP_format="4"><BehaviorTree ID="{tree_id}"><Script code="found := \'{tree_id}\'"/>'
                    "</BehaviorTree></root>")
    return path


def _main(folder: Path, include: str, tree_id: str = "Lib") -> Path:
    path = folder / "main.xml"
    path.write_text(f'<root BTCPP_format="4" main_tree_to_execute="Main"><include path="{include}"/>'
                    f'<BehaviorTree ID="Main"><SubTree ID="{tree_id}" _autoremap="true"/></BehaviorTree></root>')
    return path


def test_a_tree_outside_the_checkout_includes_the_shipped_library(tmp_path: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Failed on main: "included file 'lib/pick.xml' does not exist" (only the tree's own folder was looked in,
    and trees/ was not in the installed package)."""
    monkeypatch.delenv(TREE_PATH_VARIABLE, raising=False)
    monkeypatch.chdir(tmp_path)
    main = tmp_path / "mine.xml"
    main.write_text((REPO / "trees/stack.xml").read_text())
    tree = load_tree(main, robot_registry())
    assert {"PickObject", "PlaceOnObject", "RecoverPick", "RecoverPlace"} <= set(tree.document.trees)
    assert set(tree.sources) == {str(main), str(SHIPPED_TREES / "lib/pick.xml"), str(SHIPPED_TREES / "lib/place.xml")}


def test_the_shipped_library_is_package_data_and_the_checkouts_trees_lib() -> None:
    """One library: the checkout's trees/lib is the package's (so shipped trees and installed users read the same
    files), and pyproject.toml ships it (tests/test_package_data.py checks every data file is covered)."""
    from test_package_data import packaged

    assert sorted(p.name for p in (SHIPPED_TREES / "lib").iterdir()) == ["pick.xml", "place.xml"]
    assert {"assets/trees/lib/pick.xml", "assets/trees/lib/place.xml"} <= packaged()
    assert (REPO / "trees/lib").resolve() == (SHIPPED_TREES / "lib").resolve()
    assert (REPO / "scenes/tabletop.calibration.yaml").resolve() == \
        (SHIPPED_TREES.parent / "calibrations/tabletop.calibration.yaml").resolve()
    assert {"assets/calibrations/tabletop.calibration.yaml", "assets/calibrations/eye_in_hand.calibration.yaml"} \
        <= packaged()


def test_beside_then_the_search_path_in_order_then_the_shipped_library(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    first, second, own = tmp_path / "first", tmp_path / "second", tmp_path / "own"
    _lib(first, "Lib", "lib/pick.xml")
    _lib(second, "Second", "lib/pick.xml")
    own.mkdir()
    main = _main(own, "lib/pick.xml")
    monkeypatch.setenv(TREE_PATH_VARIABLE, os.pathsep.join([str(tmp_path / "missing"), str(first), str(second)]))
    assert load_tree(main, builtin_registry()).tick().value == "SUCCESS"
    assert str(first / "lib/pick.xml") in load_tree(main, builtin_registry()).sources
    _lib(own, "Lib", "lib/pick.xml")  # beside the tree: first
    assert str(own / "lib/pick.xml") in load_tree(main, builtin_registry()).sources
    monkeypatch.setenv(TREE_PATH_VARIABLE, "")
    (own / "lib/pick.xml").unlink()
    document = read_document(main.read_bytes(), str(main))  # last: the shipped lib/pick.xml (PickObject)
    assert str(SHIPPED_TREES / "lib/pick.xml") in document.texts and "PickObject" in document.trees


def test_an_absolute_include_is_the_users_own(tmp_path: Path) -> None:
    lib = _lib(tmp_path / "elsewhere", "Lib")
    main = _main(tmp_path, str(lib))
    tree = load_tree(main, builtin_registry())
    assert tree.tick().value == "SUCCESS" and str(lib) in tree.sources


def test_a_missing_include_names_every_place_looked(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    main = _main(tmp_path, "lib/mine.xml")
    monkeypatch.delenv(TREE_PATH_VARIABLE, raising=False)
    with pytest.raises(TreeFileError) as err:
        load_tree(main, builtin_registry())
    text = str(err.value)
    assert text.startswith(f"{main}:1: included file 'lib/mine.xml' does not exist: looked beside it "
                           f"({tmp_path / 'lib/mine.xml'}), in $BT_GRASP_TREE_PATH (not set) and in bt_grasp's "
                           f"shipped files ({SHIPPED_TREES / 'lib/mine.xml'})"), text
    monkeypatch.setenv(TREE_PATH_VARIABLE, f"/nowhere/a{os.pathsep}/nowhere/b")
    with pytest.raises(TreeFileError, match=r"\$BT_GRASP_TREE_PATH \(/nowhere/a/lib/mine.xml, /nowhere/b/lib/"):
        load_tree(main, builtin_registry())
    absolute = _main(tmp_path, "/nowhere/x.xml")
    with pytest.raises(TreeFileError, match=r"included file '/nowhere/x.xml' does not exist: looked at /nowhere/x"):
        load_tree(absolute, builtin_registry())


def test_a_log_names_each_included_file_by_the_include_that_read_it(tmp_path: Path) -> None:
    """Failed on main: every tree file was attached as tree/<its name>, so trees/lib/pick.xml became
    tree/pick.xml (and a main tree called pick.xml including lib/pick.xml lost one of the two), and the
    re-simulation looked for tree/lib/pick.xml: `replay --resim` of the shipped stack task failed."""
    stack = load_tree(REPO / "trees/stack.xml", robot_registry())
    names = tree_attachment_names(stack)
    assert sorted(names.values()) == ["tree/lib/pick.xml", "tree/lib/place.xml", "tree/stack.xml"]
    assert tree_include_links(stack) == [["tree/stack.xml", "lib/pick.xml", "tree/lib/pick.xml"],
                                         ["tree/stack.xml", "lib/place.xml", "tree/lib/place.xml"]]
    # a main tree named like an included file, an absolute include and one out of the tree's folder
    (tmp_path / "task").mkdir()
    outside = _lib(tmp_path / "other", "Other", "pick.xml")
    up = _lib(tmp_path, "Up", "up.xml")
    main = tmp_path / "task/pick.xml"
    main.write_text('<root BTCPP_format="4" main_tree_to_execute="Main"><include path="lib/pick.xml"/>'
                    f'<include path="{outside}"/><include path="../up.xml"/><BehaviorTree ID="Main"><Sequence>'
                    '<SubTree ID="Other"/><SubTree ID="Up"/></Sequence></BehaviorTree></root>')
    tree = load_tree(main, robot_registry())
    names = tree_attachment_names(tree)
    assert names[str(main)] == "tree/pick.xml"
    assert names[str(SHIPPED_TREES / "lib/pick.xml")] == "tree/lib/pick.xml"
    assert names[str(outside)].startswith("tree/include-") and names[str(outside)].endswith("/pick.xml")
    assert names[str(up)].startswith("tree/include-") and len(set(names.values())) == 4


def _as_a_log_carries_it(tree_path: Path, workdir: Path) -> tuple[dict[str, str], list[str]]:
    """What resim does with a log: the tree files written under workdir by attachment name, and its metadata."""
    from bt_grasp.episode.metadata import run_attachments
    from bt_grasp.episode.request import EpisodeRequest

    tree = load_tree(tree_path, robot_registry())
    request = EpisodeRequest(tree=tree_path, scene=REPO / "scenes/tabletop.yaml")
    files = {n: d for n, d in run_attachments(request, tree, None).items() if n.startswith("tree/")}
    for name, data in files.items():
        (workdir / name).parent.mkdir(parents=True, exist_ok=True)
        (workdir / name).write_bytes(data)
    return {"tree_includes": json.dumps(tree_include_links(tree))}, sorted(files)


def test_resim_reads_the_logs_own_copy_of_every_include(tmp_path: Path) -> None:
    """Failed on main: an absolute include ran, then `replay --resim` refused it ("lies outside ... cannot be
    re-simulated") with no way out. Now the log carries it and the re-simulation reads that copy, never the
    user's file (changed here after the run)."""
    lib = _lib(tmp_path / "mine", "Lib")
    main = _main(tmp_path / "mine", str(lib))
    workdir = tmp_path / "resim"
    meta, tree_files = _as_a_log_carries_it(main, workdir)
    lib.write_text("not a tree any more")
    links = _recorded_include_links(tmp_path / "run.mcap", meta, tree_files, workdir)
    assert links is not None
    with confined_to(workdir, "only the log's files"), recorded_includes(links):
        tree = load_tree(workdir.resolve() / "tree/main.xml", builtin_registry())
    assert tree.tick().value == "SUCCESS" and tree.root_blackboard.items() == {"found": "Lib"}
    with confined_to(workdir, "only the log's files"), recorded_includes({}), \
            pytest.raises(TreeFileError, match="is not among the files the log carries"):
        load_tree(workdir.resolve() / "tree/main.xml", builtin_registry())


@pytest.mark.parametrize(("value", "fragment"), [
    ("[[1, 2, 3]]", "is not a list of [file, include, file]"),
    ('{"a": 1}', "is not a list of [file, include, file]"),
    ('[["tree/main.xml", "x.xml", "scene/s.yaml"]]', "names 'scene/s.yaml', which is not a tree file the log"),
    ('[["tree/main.xml", "x.xml", "tree/../../etc/passwd"]]', "which is not a tree file the log carries"),
])
def test_resim_refuses_an_include_record_it_cannot_use(value: str, fragment: str, tmp_path: Path) -> None:
    with pytest.raises(LogFileError, match=fragment.replace("[", r"\[").replace("]", r"\]")):
        _recorded_include_links(tmp_path / "run.mcap", {"tree_includes": value}, ["tree/main.xml"], tmp_path)
