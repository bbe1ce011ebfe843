"""The Foxglove layouts shipped with bt_grasp (``bt_grasp/foxglove/layouts/``).

``bt_grasp.layout.json``: 3D (the arm, fixtures, point cloud, detections, grasp candidates; the judge's true
poses off by default), the camera image with the detections overlaid, a State Transitions panel with no rows,
joint-angle and gripper plots, the log and the run result: the base of the layout made for the tree that
runs (``bt_grasp.foxglove.tree_layout`` fills in one row per leaf of that tree, by path).

``bt_grasp_control.layout.json`` (a run with ``--live --control``): the same panels and, on the right, the
stock Parameters panel (the run's state, breakpoints, settings, object choice and faults:
``bt_grasp.foxglove.control``) above Publish buttons that send commands on ``/control/command``. It is made
from the first by :func:`control_layout`; a test keeps the shipped file equal to it.
"""

from __future__ import annotations

import json
from importlib.resources import files
from pathlib import Path

from bt_grasp.files.json_types import JsonObject, JsonValue

#: the topic a Foxglove client publishes JSON commands on (the Publish panel's topic)
COMMAND_TOPIC = "/control/command"
#: the schema name a client advertises it with (the Publish panel's datatype; the server does not require it)
COMMAND_SCHEMA = "bt_grasp.Command"
#: the Publish panels of the control layout: (panel id, button text, colour, the JSON command it sends)
CONTROL_BUTTONS: tuple[tuple[str, str, str, JsonObject], ...] = (
    ("Publish!pause", "Pause", "#c77c02", {"kind": "pause"}),
    ("Publish!resume", "Resume", "#00a871", {"kind": "resume"}),
    ("Publish!step", "Step 1 tick", "#2f6fba", {"kind": "step", "n": 1}),
    ("Publish!stop", "Stop run", "#c0392b", {"kind": "stop"}),
)


def layout_path() -> Path:
    return Path(str(files("bt_grasp") / "foxglove" / "layouts" / "bt_grasp.layout.json"))


def control_layout_path() -> Path:
    return Path(str(files("bt_grasp") / "foxglove" / "layouts" / "bt_grasp_control.layout.json"))


def control_layout() -> JsonObject:
    """The shipped control layout: the main layout's panels beside a Parameters panel and the command buttons."""
    layout: JsonObject = json.loads(layout_path().read_text())
    return with_control_panels(layout)


def with_control_panels(base: JsonObject) -> JsonObject:
    """A layout (the shipped one, or a tree's own: ``tree_layout.layout_for_structure``) with the control panels
    on its right: the Parameters panel above the Publish buttons of :data:`CONTROL_BUTTONS`."""
    panels = base["configById"]
    assert isinstance(panels, dict)  # a Foxglove layout's panels by id
    config = dict(panels)
    config["Parameters!control"] = {"title": "bt_grasp control (Parameters)"}
    for panel_id, text, colour, command in CONTROL_BUTTONS:
        config[panel_id] = {"topicName": COMMAND_TOPIC, "datatype": COMMAND_SCHEMA, "buttonText": text,
                            "buttonTooltip": json.dumps(command), "buttonColor": colour, "advancedView": False,
                            "value": json.dumps(command)}
    ids = [b[0] for b in CONTROL_BUTTONS]
    buttons: JsonValue = {"direction": "row", "first": ids[-2], "second": ids[-1]}
    buttons = {"direction": "row", "first": {"direction": "row", "first": ids[0], "second": ids[1]},
               "second": buttons}
    side: JsonObject = {"direction": "column", "first": "Parameters!control", "second": buttons,
                        "splitPercentage": 84}
    layout: JsonObject = {"direction": "row", "first": base["layout"], "second": side, "splitPercentage": 66}
    return {**base, "configById": config, "layout": layout}


def write_control_layout(path: Path | None = None) -> Path:
    """Write :func:`control_layout` to the shipped file (after the main layout changed)."""
    target = path or control_layout_path()
    target.write_text(json.dumps(control_layout(), indent=2) + "\n")
    return target
