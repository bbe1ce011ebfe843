"""A harness for semantic tests: ``Stub`` leaves whose statuses a test scripts, tick by tick."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from bt_grasp.clock import ManualClock
from bt_grasp.nodes import Leaf, NodeContext, Status, action, condition, output_port
from bt_grasp.tree import BtNode, LoadedTree, builtin_registry, load_tree_from_string
from bt_grasp.tree.introspect import bt_status_name

S, F, R, K = "SUCCESS", "FAILURE", "RUNNING", "SKIPPED"
_STATUS = {S: Status.SUCCESS, F: Status.FAILURE, R: Status.RUNNING, K: Status.SKIPPED}


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
        return _STATUS[status]

    @property
    def halted(self) -> int:
        return self.terminated.count("IDLE")


_OUT = output_port("out", object, default="{=}")


@action(name="Stub", ports=[_OUT])
class StubLeaf(Leaf):
    """A leaf whose statuses the test scripts."""

    def __init__(self, ctx: NodeContext, harness: Harness) -> None:
        super().__init__(ctx)
        self.stub = harness.stubs.setdefault(ctx.name, Stub())

    def initialise(self) -> None:
        self.stub.initialised += 1

    def update(self) -> Status:
        self.stub.ticks += 1
        if self.ports.has("out"):
            self.ports.set("out", self.stub.ticks)
        return self.stub.next()

    def terminate(self, new_status: Status) -> None:
        self.stub.terminated.append(new_status.name)


@condition(name="Check", ports=[_OUT])
class StubCheck(StubLeaf):
    """A condition whose statuses the test scripts."""


@action(name="Arm", needs_robot=True)
class StubArm(StubLeaf):
    """A robot leaf whose statuses the test scripts (one update per control period)."""


class Harness:
    """Load ``xml`` (a full file, or the body of one ``<BehaviorTree ID="Main">``) with Stub leaves; ``extra``
    node classes (declared with the node API) are registered too."""

    def __init__(self, xml: str, extra: tuple[type[BtNode], ...] = (), **kwargs: object) -> None:
        self.stubs: dict[str, Stub] = {}
        self.registry = builtin_registry()
        for node in (StubLeaf, StubCheck, StubArm):
            self.registry.register(node, args=(self,))
        for node_class in extra:
            self.registry.register(node_class)
        if not xml.lstrip().startswith("<root"):
            xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{xml}</BehaviorTree></root>'
        self.clock = ManualClock()
        self.tree: LoadedTree = load_tree_from_string(xml, self.registry, clock=self.clock, **kwargs)  # type: ignore[arg-type]

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
