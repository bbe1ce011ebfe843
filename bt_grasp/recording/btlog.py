"""Export a recorded run as a BehaviorTree.CPP 4 ``FileLogger2`` file (.btlog, for Groot2), and read one.

Layout (little-endian), as BT.CPP 4's ``FileLogger2`` writes it:

- the 18 ASCII bytes ``BTCPP4-FileLogger2``, then one protocol byte (1);
- int32: length N of the tree XML, then the N bytes of XML (``<root BTCPP_format="4">`` with one
  ``<BehaviorTree>`` per (sub)tree, every node carrying ``_uid`` and ``_fullpath``, and a
  ``<TreeNodesModel>`` describing the non-built-in node types);
- int64: the start time, microseconds since the Unix epoch;
- then 9-byte transitions: 6 bytes time since the start (µs, unsigned), 2 bytes node uid, 1 byte status
  (IDLE 0, RUNNING 1, SUCCESS 2, FAILURE 3, SKIPPED 4).

Transition times are simulated time since the first recorded tick.
"""

from __future__ import annotations

import re
import struct
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import defusedxml.ElementTree as SafeET

from bt_grasp.errors import InputError, LogFileError
from bt_grasp.files.bounded_io import MAX_RESULTS_BYTES, read_user_file
from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.files.output_files import write_output_file
from bt_grasp.recording.messages import LoggedTreeNode
from bt_grasp.recording.reader import RunLog
from bt_grasp.recording.replay import status_changes
from bt_grasp.tree.records import TreeNode
from bt_grasp.tree.registry import NodeKind

MAGIC = b"BTCPP4-FileLogger2"
PROTOCOL = 1
STATUS_CODES = {"IDLE": 0, "RUNNING": 1, "SUCCESS": 2, "FAILURE": 3, "SKIPPED": 4}
STATUS_NAMES = {code: name for name, code in STATUS_CODES.items()}
_MAX_TIME_US = (1 << 48) - 1
#: leaf kinds as the tree introspection writes them (``NodeKind.value``) -> the .btlog model's tag
_LEAF_TAGS = {NodeKind.ACTION.value: "Action", NodeKind.CONDITION.value: "Condition"}


@dataclass(frozen=True)
class Transition:
    timestamp_us: int  # since the start time
    uid: int
    status: str


@dataclass(frozen=True)
class BtLog:
    protocol: int
    xml: str
    start_time_us: int
    transitions: tuple[Transition, ...]
    nodes: dict[int, dict[str, str]]  # uid -> {"tag", "name", "fullpath"}


#: a node type or attribute name becomes an XML tag or attribute name: it must be one
_XML_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]{0,200}$")
#: characters XML 1.0 cannot hold at all, even escaped
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


class NotExportable(ValueError):
    """A recorded structure holds a name XML cannot carry (a log written by something else than bt_grasp)."""


def _text(value: object) -> str:
    return _NOT_XML.sub("\ufffd", str(value))


def _name(value: object, what: str) -> str:
    text = str(value)
    if not _XML_NAME.match(text):
        raise NotExportable(f"its tree holds a {what} {text[:60]!r}, which is not an XML name")
    return text


def _attr(value: JsonValue) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return _text(value)


def tree_xml(structure: LoggedTreeNode, main_tree_id: str = "MainTree") -> str:
    """The BT.CPP 4 XML of a recorded structure, every node with ``_uid`` and ``_fullpath``."""
    main_tree_id = _text(main_tree_id)
    root = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": main_tree_id})
    models: dict[str, tuple[str, list[str]]] = {}
    pending: list[tuple[str, str, LoggedTreeNode]] = [(main_tree_id, "", structure)]
    while pending:
        tree_id, fullpath, top = pending.pop(0)
        tree_elem = ET.SubElement(root, "BehaviorTree", {"ID": tree_id, "_fullpath": fullpath})
        _add_node(tree_elem, top, models, pending)
    model_root = ET.SubElement(root, "TreeNodesModel")
    for type_name, (tag, ports) in sorted(models.items()):
        model = ET.SubElement(model_root, tag, {"ID": type_name})
        for port in ports:
            ET.SubElement(model, "input_port", {"name": port})
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")


def _add_node(
    parent: ET.Element, node: LoggedTreeNode, models: dict[str, tuple[str, list[str]]],
    pending: list[tuple[str, str, LoggedTreeNode]],
) -> None:
    given = (node.get("attributes") or {}).items()
    attributes = {_name(k, "port name"): v for k, v in given if k not in ("name", "ID")}
    kind = str(node.get("kind", ""))
    uid, path = int(node["uid"]), _text(node.get("path", ""))
    if not 0 <= uid <= 0xFFFF:
        raise InputError("--export-btlog", f"node uid {uid} does not fit the .btlog format's 16 bits")
    if kind == NodeKind.SUBTREE.value:
        subtree_id = _text((node.get("attributes") or {}).get("ID") or node.get("name") or "SubTree")
        attrs = {"ID": subtree_id, "_uid": str(uid), "_fullpath": path}
        ET.SubElement(parent, "SubTree", {**attrs, **{k: _attr(v) for k, v in attributes.items()}})
        for child in node.get("children", []):
            pending.append((subtree_id, path, child))
        return
    type_name = _name(node.get("type", "") or "Action", "node type")
    attrs = {"name": _text(node.get("name", "")), "_uid": str(uid), "_fullpath": path}
    elem = ET.SubElement(parent, type_name, {**attrs, **{k: _attr(v) for k, v in attributes.items()}})
    if kind in _LEAF_TAGS:
        ports = sorted(k for k in attributes if not k.startswith("_"))
        models.setdefault(type_name, (_LEAF_TAGS[kind], ports))
    for child in node.get("children", []):
        _add_node(elem, child, models, pending)


def transitions(run: RunLog) -> list[Transition]:
    """Every status change of the run, timed in simulated µs since the first tick."""
    if not run.ticks:
        return []
    first = run.ticks[0].stamp_ns
    out = []
    for change in status_changes(run):
        ts = (change.stamp_ns - first) // 1000
        if not 0 <= ts <= _MAX_TIME_US:
            raise InputError("--export-btlog", f"tick {change.tick} lies outside the .btlog time range")
        out.append(Transition(ts, change.uid, change.new))
    return out


def write_btlog(run: RunLog, path: str | Path) -> BtLog:
    """Write ``run`` as a .btlog file; returns what was written."""
    target = Path(path)
    if target.suffix != ".btlog":
        raise InputError("--export-btlog", f"{target} must end in .btlog (Groot2 opens only that)")
    if not run.structures:
        raise InputError("--export-btlog", f"{run.path.name} holds no tree structure to export")
    try:
        xml = tree_xml(run.structures[-1].root, run.metadata.get("main_tree", "MainTree"))
    except NotExportable as exc:
        raise LogFileError(run.path, f"cannot be exported as .btlog: {exc}") from None
    nodes = _xml_nodes(xml, run.path)  # checked before anything is written
    start = run.metadata.get("start_unix_ns", "0") or "0"
    if not (start.isascii() and start.isdigit() and len(start) < 20):
        raise LogFileError(run.path, f"its run metadata 'start_unix_ns' is {start[:40]!r}, not a time in nanoseconds")
    start_us = int(start) // 1000
    moves = transitions(run)
    unknown = next((t for t in moves if t.status not in STATUS_CODES), None)
    if unknown is not None:
        raise LogFileError(run.path, f"node {unknown.uid} has the status {unknown.status[:40]!r}, which a .btlog "
                                     "cannot hold")
    write_output_file(target, encode_btlog(xml, start_us, moves), "--export-btlog", example="run.btlog")
    return BtLog(PROTOCOL, xml, start_us, tuple(moves), nodes)


def encode_btlog(xml: str, start_us: int, moves: Sequence[Transition]) -> bytes:
    """The bytes of a .btlog: header, tree XML, start time, transitions (see the module)."""
    body = bytearray(MAGIC)
    body += struct.pack("<B", PROTOCOL)
    xml_bytes = xml.encode("utf-8")
    body += struct.pack("<i", len(xml_bytes)) + xml_bytes
    body += struct.pack("<q", start_us)
    for t in moves:
        body += t.timestamp_us.to_bytes(6, "little") + struct.pack("<HB", t.uid, STATUS_CODES[t.status])
    return bytes(body)


def logged_structure(node: TreeNode) -> LoggedTreeNode:
    """A built tree's structure (``bt_grasp.tree.introspect.tree_structure``) as a log holds it."""
    attributes: JsonObject = dict(node["attributes"])
    return {"uid": node["uid"], "path": node["path"], "type": node["type"], "name": node["name"],
            "kind": node["kind"], "attributes": attributes,
            "children": [logged_structure(child) for child in node["children"]]}


def write_walk_btlog(path: str | Path, structure: TreeNode, main_tree: str, start_unix_ns: int,
                     moves: Sequence[Transition]) -> BtLog:
    """Write a run that was never logged (a dry run's walk: every status change, timed in simulated µs since the
    first tick) as a .btlog, with the writer ``replay --export-btlog`` uses."""
    target = Path(path)
    if target.suffix != ".btlog":
        raise InputError("--export-btlog", f"{target} must end in .btlog (Groot2 opens only that)")
    try:
        xml = tree_xml(logged_structure(structure), main_tree)
    except NotExportable as exc:
        raise InputError("--export-btlog", f"the tree cannot be exported as .btlog: {exc}") from None
    for move in moves:
        if not 0 <= move.timestamp_us <= _MAX_TIME_US:
            raise InputError("--export-btlog", f"a transition at {move.timestamp_us} µs lies outside the .btlog "
                             "time range")
    start_us = start_unix_ns // 1000
    write_output_file(target, encode_btlog(xml, start_us, moves), "--export-btlog", example="run.btlog")
    return BtLog(PROTOCOL, xml, start_us, tuple(moves), _xml_nodes(xml, target))


def _xml_nodes(xml: str, path: Path) -> dict[int, dict[str, str]]:
    try:
        root = SafeET.fromstring(xml)
    except Exception as exc:
        raise LogFileError(path, "holds tree XML that does not parse") from exc
    return {
        int(elem.get("_uid")): {"tag": elem.tag, "name": elem.get("name", elem.get("ID", "")),
                                "fullpath": elem.get("_fullpath", "")}
        for elem in root.iter() if elem.get("_uid") is not None
    }


def read_btlog(path: str | Path) -> BtLog:
    """Parse a BT.CPP 4 FileLogger2 file; raises ``LogFileError`` for anything else."""
    p = Path(path)
    data = read_user_file(p, MAX_RESULTS_BYTES, error=LogFileError)  # a regular file, at most 1 GB
    if not data.startswith(MAGIC):
        raise LogFileError(p, "is not a BT.CPP FileLogger2 file (no BTCPP4-FileLogger2 header)")
    offset = len(MAGIC)
    header = offset + 1 + 4
    if len(data) < header:
        raise LogFileError(p, "is cut off inside its header")
    protocol = data[offset]
    (xml_len,) = struct.unpack_from("<i", data, offset + 1)
    if xml_len < 0 or len(data) < header + xml_len + 8:
        raise LogFileError(p, "is cut off inside its tree XML or start time")
    xml = data[header: header + xml_len].decode("utf-8")
    (start_us,) = struct.unpack_from("<q", data, header + xml_len)
    rest = data[header + xml_len + 8:]
    if len(rest) % 9:
        raise LogFileError(p, f"ends in a partial transition ({len(rest) % 9} stray bytes)")
    moves = []
    for i in range(0, len(rest), 9):
        ts = int.from_bytes(rest[i: i + 6], "little")
        uid, code = struct.unpack_from("<HB", rest, i + 6)
        if code not in STATUS_NAMES:
            raise LogFileError(p, f"has an unknown status code {code} in transition {i // 9}")
        moves.append(Transition(ts, uid, STATUS_NAMES[code]))
    return BtLog(protocol, xml, start_us, tuple(moves), _xml_nodes(xml, p))
