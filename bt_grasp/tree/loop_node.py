"""BT.CPP's ``LoopNode<T>`` (``decorators/loop_node.h``) over items of any type: :func:`loop_node`.

Each tick, when the child is not RUNNING, the node pops the front of ``queue`` into the output ``value`` and
ticks the child; it returns RUNNING after a child SUCCESS (the next item comes next tick), FAILURE when the
child fails, and ``if_empty`` (SUCCESS by default) once the queue is empty. ``queue`` is either a literal
(``"1;2;3"``, converted at load time, so a wrong item is a load error; split as BT.CPP does, so ``""`` is an
empty queue and ``"1;2;"`` two items) or a blackboard entry holding

* a :class:`collections.deque`: shared, popped in place (BT.CPP's ``SharedQueue<T>``);
* a ``list`` or ``tuple``: copied once when the loop starts (BT.CPP accepts a ``std::vector<T>``);
* a string: parsed once when the loop starts, items separated by ``;``.

An application declares a loop over its own type, e.g. over a list of perceived objects, and registers it as any
node::

    LoopObjects = loop_node("LoopObjects", PerceivedObject, description="every perceived object")
    registry.register(LoopObjects)

The items of a blackboard queue must be of the loop's type (an ``int`` is accepted by LoopDouble).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from bt_grasp.tree.blackboard import EMPTY
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.declare import decorator, inout_port, input_port, output_port
from bt_grasp.tree.decorator_node import Decorator
from bt_grasp.tree.exceptions import PortValueError, TreeRuntimeError
from bt_grasp.tree.node import BtStatus
from bt_grasp.tree.ports import blackboard_key

Parser = Callable[[str], object]


def split_items(text: str) -> list[str]:
    """The items of a text queue, split as BT.CPP's ``splitString(text, ';')``: an empty text is an empty
    queue and a trailing ``;`` ends the last item (``"1;2;"`` is two items), but ``"1;;2"`` holds an empty
    item."""
    parts = text.split(";")
    if parts[-1] == "":
        parts.pop()
    return parts


class Loop(Decorator):
    """The loop node; the classes :func:`loop_node` declares set ``item_type`` and ``parse_item``."""

    item_type: type = object
    parse_item: Parser | None = None

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        raw = ctx.attributes.get("queue", "")
        self.static_queue: tuple[object, ...] | None = None
        if blackboard_key(raw, "queue") is None:
            self.static_queue = tuple(self._parse_text(raw))
        self.queue: deque[object] | None = None
        self.child_running = False

    @classmethod
    def _parse_text(cls, text: str) -> list[object]:
        parse = cls.parse_item
        if parse is None:
            raise PortValueError(f"port 'queue': a {cls.item_type.__name__} queue cannot be written as text")
        items = []
        for part in split_items(text):
            try:
                items.append(parse(part))
            except (TreeRuntimeError, ValueError) as exc:
                raise PortValueError(f"port 'queue': item {part!r} is not a {cls.item_type.__name__} ({exc})") from None
        return items

    def _check(self, items: deque[object]) -> deque[object]:
        wanted = (int, float) if self.item_type is float else self.item_type
        for item in items:
            if not isinstance(item, wanted) or (self.item_type is int and isinstance(item, bool)):
                raise TreeRuntimeError(
                    f"{self.bt_path}: the queue holds {item!r} ({type(item).__name__}), not a {self.item_type.__name__}"
                )
        return items

    def _read_queue(self) -> None:
        key = self.ports.key("queue")
        assert key is not None
        entry = self.blackboard.entry(key)
        if entry is None or entry.value is EMPTY:
            return
        raw = entry.value
        if isinstance(raw, deque):
            self.queue = self._check(raw)
        elif self.queue is None:
            if isinstance(raw, list | tuple):
                self.queue = self._check(deque(raw))
            elif isinstance(raw, str):
                try:
                    self.queue = deque(self._parse_text(raw))
                except PortValueError as exc:
                    raise TreeRuntimeError(f"{self.bt_path}: {exc} (from blackboard entry '{key}')") from None
            else:
                raise TreeRuntimeError(
                    f"{self.bt_path}: port 'queue' must hold a deque, a list or a string, not {type(raw).__name__}"
                )

    def bt_tick(self) -> BtStatus:
        popped = False
        if self.bt_state is BtStatus.IDLE:
            self.child_running = False
            self.queue = deque(self.static_queue) if self.static_queue is not None else None
        if not self.child_running:
            if self.static_queue is None:
                self._read_queue()
            if self.queue:
                self.ports.set("value", self.queue.popleft())
                popped = True
        if not popped and not self.child_running:
            return BtStatus(self.ports.require("if_empty", str))
        if self.bt_state is BtStatus.IDLE:
            self.set_bt_status(BtStatus.RUNNING)
        status = self.tick_child()
        self.child_running = status is BtStatus.RUNNING
        if status.completed:
            self.reset_child()
        return BtStatus.FAILURE if status is BtStatus.FAILURE else BtStatus.RUNNING

    def halt(self) -> None:
        self.child_running = False
        super().halt()


def loop_node(name: str, item_type: type, parse_item: Parser | None = None, description: str = "") -> type[Loop]:
    """Declare a ``Loop*`` node over items of ``item_type`` (BT.CPP's ``LoopNode<T>``), ready for
    ``registry.register``. ``parse_item`` converts one ``;``-separated item of a text queue (None: the queue must
    be a blackboard entry holding a deque or list)."""
    namespace = {"item_type": item_type, "parse_item": staticmethod(parse_item) if parse_item else None,
                 "__doc__": f"Pops each {item_type.__name__} of queue into value and ticks the child."}
    cls = type(name, (Loop,), namespace)
    ports = (
        inout_port("queue", object, f"the {item_type.__name__} items: a blackboard queue or 'a;b;c'", required=True),
        input_port("if_empty", str, "SUCCESS", "status once the queue is empty",
                   choices=("SUCCESS", "FAILURE", "SKIPPED")),
        output_port("value", item_type, "the current item"),
    )
    return decorator(name=name, ports=ports, description=description or None)(cls)
