"""``--device [SERIAL]``: an option whose value may be left out (typer has none), as ``run --live [PORT]`` does.

``--device`` followed by nothing or by another option becomes ``--device=`` (the empty serial: the only device
connected); ``--device 123456789012`` keeps its serial number.
"""

from __future__ import annotations

#: the commands whose command lines are rewritten (``bt_grasp.cli.main``)
COMMANDS = ("perceive", "camera")


def fill_device_value(args: list[str]) -> list[str]:
    out: list[str] = []
    for i, token in enumerate(args):
        if token == "--device" and (i + 1 >= len(args) or args[i + 1].startswith("-")):
            out.append("--device=")
        else:
            out.append(token)
    return out
