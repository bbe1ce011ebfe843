"""The type of JSON data: what a log's JSON messages, a run's result and a campaign's results file hold.

One alias for every package (this package sits on a floor every other one may import). A value read from a
file has this type until it is checked; a checked message gets its own ``TypedDict`` (the log's messages:
``bt_grasp.recording.messages``; a results row: ``bt_grasp.campaign.results``).
"""

from __future__ import annotations

from typing import TypeAlias

JsonScalar: TypeAlias = str | int | float | bool | None
JsonValue: TypeAlias = JsonScalar | list["JsonValue"] | dict[str, "JsonValue"]
JsonObject: TypeAlias = dict[str, JsonValue]
