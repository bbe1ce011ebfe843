"""What a run's result says of each fault that fired (a leaf module: the result, the resident's protocol and the
campaign's rows read it without the injector)."""

from __future__ import annotations

from dataclasses import dataclass

from bt_grasp.files.json_types import JsonObject


@dataclass(frozen=True)
class FaultFiring:
    """One firing of a fault as a run's result reports it: which fault, at which tick, armed by which leaf, and the
    object it pushed (``object_nudge``) with whether a finger touched that object at any time in the run: a push
    on an object the tree never touched is not a push on what it grasped, and the result says so."""

    label: str
    kind: str
    tick: int
    leaf: str | None
    target: str | None = None
    target_touched: bool | None = None

    @property
    def missed(self) -> bool:
        """It pushed an object the tree never touched."""
        return self.target is not None and self.target_touched is False

    def sentence(self) -> str:
        text = f"{self.label} at tick {self.tick}"
        if self.target is not None:
            text += f" pushed {self.target}"
        if self.missed:
            text += (f"; the tree never touched {self.target} (to push the object the tree grasps, name it in "
                     "the plan: params.object)")
        return text

    def to_json(self) -> JsonObject:
        return {"label": self.label, "kind": self.kind, "tick": self.tick, "leaf": self.leaf, "target": self.target,
                "target_touched": self.target_touched}
