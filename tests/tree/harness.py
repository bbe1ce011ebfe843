"""A harness for semantic tests: ``Stub`` leaves whose statuses a test scripts, tick by tick."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from py_trees.common import Status

from bt_grasp.clock import ManualClock
from bt_grasp.tree import (
    BtNode,
    Leaf,
    LoadedTree,
    NodeContext,
    NodeKind,
    NodeSpec,
    PortDirection,
    PortSpec,
    builtin_registry,
    load_tree_from_string,
)
from bt_grasp.tree.introspect import bt_status_name

S, F, R = "SUCCESS", "FAILURE", "RUNNING"
_PY = {S: Status.SUCCESS, F: Status.FAILURE, R: Status.RUNNING}


@dataclass
class Stub:
    """Scripted behaviour of one stand-in leaf: the queued statuses (the last one repeats)."""

    queue: list[str] = field(default_factory=lambda: [S])
    ticks: int = 0
    initialised: int = 0
    terminated: list[str] = field(default_factory=list)

    def returns(self, *statuses: str) -> Stub:
        self.queue = list(statuses)
        return self

    def next(self) -> Status:
        status = self.queue.pop(0) if len(self.queue) > 1 else self.queue[0]
        return _PY[status]

    @property
    def halted(self) -> int:
        return self.terminated.count("INVALID")


class StubLeaf(Leaf):
    def __init__(self, ctx: NodeContext, stub: Stub) -> None:
        super().__init__(ctx)
        self.stub = stub

    def initialise(self) -> None:
        self.stub.initialised += 1

    def update(self) -> Status:
        self.stub.ticks += 1
        if self.ports.has("out"):
            self.ports.set("out", self.stub.ticks)
        return self.stub.next()

    def terminate(self, new_status: Status) -> None:
        self.stub.terminated.append(new_status.name)


class Harness:
    """Load ``xml`` (a full file, or the body of one ``<BehaviorTree ID="Main">``) with Stub leaves."""

    def __init__(self, xml: str, extra_specs: tuple[NodeSpec, ...] = (), **kwargs: object) -> None:
        self.stubs: dict[str, Stub] = {}
        self.registry = builtin_registry()
        out = PortSpec("out", PortDirection.OUTPUT, object, "{=}")
        for kind, type_id in ((NodeKind.ACTION, "Stub"), (NodeKind.CONDITION, "Check")):
            self.registry.register(NodeSpec(type_id, kind, (out,), self._factory))
        self.registry.register(NodeSpec("Arm", NodeKind.ACTION, (), self._factory, needs_robot=True))
        for spec in extra_specs:
            self.registry.register(spec)
        if not xml.lstrip().startswith("<root"):
            xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{xml}</BehaviorTree></root>'
        self.clock = ManualClock()
        self.tree: LoadedTree = load_tree_from_string(xml, self.registry, clock=self.clock, **kwargs)  # type: ignore[arg-type]

    def _factory(self, ctx: NodeContext) -> StubLeaf:
        return StubLeaf(ctx, self.stubs.setdefault(ctx.name, Stub()))

    def __getitem__(self, name: str) -> Stub:
        return self.stubs[name]

    def tick(self) -> str:
        return self.tree.tick().value

    def state(self, name: str) -> str:
        """The BT.CPP status of the node with this name (or path)."""
        return bt_status_name(self.tree.find(name))

    def node(self, name: str) -> BtNode:
        return self.tree.find(name)

    @property
    def bb(self) -> dict[str, object]:
        return self.tree.root_blackboard.items()

    def nodes(self) -> Iterator[BtNode]:
        return self.tree.nodes()
