"""The one gate from a name in a file to a path on disk refuses every way out of its folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bt_grasp.errors import InputError
from bt_grasp.files.safe_path import check_relative_name, file_component, join_under


@pytest.mark.parametrize("name", ["tree/pick.xml", "tree/lib/pick.xml", "scene.yaml", "a.b-c_d"])
def test_plain_relative_names_pass(name: str, tmp_path: Path) -> None:
    assert join_under(tmp_path, name, source="x.mcap") == tmp_path.resolve() / name


@pytest.mark.parametrize(
    ("name", "fragment"),
    [
        ("../evil", "'..' part"),
        ("tree/../../evil", "'..' part"),
        ("/etc/passwd", "absolute"),
        ("~/.bashrc", "absolute"),
        ("C:evil", "absolute"),
        ("a\\..\\b", "backslash"),
        ("a\x00b", "control character"),
        ("a//b", "empty"),
        ("./a", "'.' part"),
        ("", "empty"),
        ("x" * 300, "longer than 255"),
    ],
)
def test_hostile_names_are_refused_with_the_file_named(name: str, fragment: str, tmp_path: Path) -> None:
    with pytest.raises(InputError) as info:
        join_under(tmp_path, name, source="shared.mcap", what="attachment name")
    assert info.value.message.startswith("shared.mcap: attachment name") or "empty" in info.value.message
    assert fragment in info.value.message


def test_a_symbolic_link_out_of_the_folder_is_refused(tmp_path: Path) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    root = tmp_path / "root"
    root.mkdir()
    os.symlink(outside, root / "link")
    with pytest.raises(InputError, match="outside"):
        join_under(root, "link/file.txt", source="x.mcap")
    check_relative_name("link/file.txt", source="x.mcap")  # the name alone is fine; the link is what escapes


@pytest.mark.parametrize("label", ["../../etc", "a/b", "..", ".hidden", "x\x00y", "name with spaces", "é"])
def test_file_component_is_always_one_plain_part(label: str) -> None:
    part = file_component(label)
    assert "/" not in part and "\x00" not in part and not part.startswith(".")
    check_relative_name(part, source="t")


def test_file_component_keeps_plain_labels_and_separates_lookalikes() -> None:
    assert file_component("tabletop") == "tabletop"
    assert file_component("a/b") != file_component("a_b")
