"""One node API (issue 38, findings 1, 4 and 5): one way to declare leaves, controls and decorators, used by
bt_grasp's own nodes and by plugins alike; public calls for what a control does to its children; nodes from a
function (BT.CPP's registerSimpleAction/Condition); duplicates named with who registered first; installed plugins
chosen per command; ``tree models`` for the plugins alone, with Groot2's type names.

On main as it was: robot leaves used ``@leaf(registry, ...)`` and a ``DECLARED_REASONS`` table patched onto their
specs, the built-ins ``manifest.py`` builders; ``_tick_child`` was the way to tick a child; no simple nodes; a
duplicate reason said only "already registered"; ``tree models`` mixed bt_grasp's leaves with a plugin's and gave
custom types no ``type=``; warnings said ``float`` where Groot2 says ``double``.
"""

from __future__ import annotations

import ast
import logging
import re
from pathlib import Path

import pytest

from bt_grasp.behaviours.library import robot_registry
from bt_grasp.cli.main import main
from bt_grasp.nodes import (
    Control,
    DeclarationError,
    Leaf,
    NodeContext,
    NodeRegistry,
    Reason,
    Status,
    action,
    control,
    input_port,
    output_port,
)
from bt_grasp.tree import builtin_registry, load_tree_from_string
from bt_grasp.tree.exceptions import TreeRuntimeError

from .conftest import FakeEntryPoint

REPO = Path(__file__).resolve().parents[2]
PLUGIN = Path(__file__).parent / "data" / "user_nodes.py"
S, F, R = Status.SUCCESS, Status.FAILURE, Status.RUNNING


def _tree(body: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


# ---- finding 1: one way to declare a node ---------------------------------------------------------------------


def test_every_shipped_node_is_a_class_declared_and_registered_with_the_node_api() -> None:
    registry = robot_registry(installed=False)
    assert len(registry) == 76  # BT.CPP's 42 built-ins and bt_grasp's 34 robot leaves
    for spec in registry.specs():
        node_class = spec.factory
        assert isinstance(node_class, type), spec.name
        assert node_class.__dict__.get("bt_spec") is spec, spec.name  # its own declaration, registered as is
    assert registry["Grasp"].failure_reasons == ("GRASP_EMPTY", "TIMEOUT")  # declared on the leaf, no table


SPEC_RECORDS = ("NodeSpec(", "PortSpec(")
#: the registry's own records and the engine's internal node types (the SubTree stand-in, a test stand-in, BT.CPP's
#: TestNode of a substitution rule), and the node types a TreeNodesModel declares (records made from Groot2's data)
RECORD_MODULES = {"tree/registry.py", "tree/declare.py", "tree/builder.py", "tree/substitution.py", "tree/test_node.py",
                  "tree/model_stand_ins.py"}


def test_no_other_way_to_declare_a_node_is_left_in_the_package() -> None:
    offenders = []
    for path in sorted((REPO / "bt_grasp").rglob("*.py")):
        relative = path.relative_to(REPO / "bt_grasp").as_posix()
        text = path.read_text()
        if relative not in RECORD_MODULES and any(record in text for record in SPEC_RECORDS):
            offenders.append(relative)
        tree = ast.parse(text)
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef) and any(
                    isinstance(d, ast.Call) and getattr(d.func, "id", "") == "leaf" for d in node.decorator_list):
                offenders.append(f"{relative}: @leaf on {node.name}")
    assert not (REPO / "bt_grasp/tree/builtins/manifest.py").exists()
    assert offenders == []


OLD_WAYS = ("PortSpec(", "NodeSpec(", ".bt_spec", "@leaf(", "_tick_child", "BtStatus", "from bt_grasp.tree import Leaf",
            "self.kids", "self.failed(", "Status.INVALID", "input_float(", "py_trees.common import Status")


def test_the_docs_and_the_example_use_only_the_node_api() -> None:
    pages = [*sorted((REPO / "docs").glob("*.md")), REPO / "README.md"]
    example = sorted((REPO / "examples").rglob("*.py"))
    offenders = []
    for path in [*pages, *example]:
        text = path.read_text()
        code = "\n".join(re.findall(r"```python\n(.*?)```", text, re.S)) if path.suffix == ".md" else text
        offenders += [f"{path.relative_to(REPO)}: {old}" for old in OLD_WAYS if old in code]
    assert offenders == []


OLD_NAMES = [("bt_grasp.tree", n) for n in ("leaf", "Leaf", "NodeContext", "PortSpec", "PortDirection", "NodeKind",
                                             "NodeSpec", "NO_DEFAULT")]
OLD_NAMES += [("bt_grasp.nodes", n) for n in ("BtStatus", "PortSpec", "PortDirection", "NodeSpec", "NodeKind",
                                              "NO_DEFAULT", "leaf")]
OLD_NAMES += [("bt_grasp.tree.builtins.loops", "loop_spec")]


@pytest.mark.parametrize(("module", "name"), OLD_NAMES)
def test_an_old_name_is_an_error_naming_the_new_call(module: str, name: str) -> None:
    with pytest.raises(ImportError, match=rf"{re.escape(module)}\.{name} is gone: use "):
        exec(f"from {module} import {name}", {})


def test_the_migration_table_lists_every_old_name() -> None:
    from bt_grasp.tree.removed import REMOVED

    assert sorted((m, n) for m, names in REMOVED.items() for n in names) == sorted(OLD_NAMES)
    page = (REPO / "docs" / "own-leaves.md").read_text()
    table = page.split("## Migrating from the earlier node API", 1)[1].split("\n## ", 1)[0]
    missing = [f"{m}.{n}" for m, names in REMOVED.items() for n in names if f"`{m}.{n}`" not in table]
    assert missing == []


def test_registering_a_spec_or_an_undeclared_class_names_the_call() -> None:
    @action()
    class Beep(Leaf):
        def update(self) -> Status:
            return Status.SUCCESS

    registry = builtin_registry()
    with pytest.raises(DeclarationError, match=r"register\(\) takes the node class, not its spec: "
                                               r"registry.register\(Beep\)"):
        registry.register(Beep.bt_spec)  # type: ignore[attr-defined, arg-type]

    class Boop(Beep):  # a subclass is a new node type: it has no declaration of its own
        pass

    with pytest.raises(DeclarationError, match="Boop is not declared: decorate the class with @action"):
        registry.register(Boop)


# ---- finding 4: the calls a control makes on its children ------------------------------------------------------


@action(ports=[input_port("ticks", int, 1, "RUNNING for ticks - 1 ticks, then SUCCESS")])
class Work(Leaf):
    """Runs for a while; counts its halts in the root blackboard's ``halts``."""

    def initialise(self) -> None:
        self.done = 0

    def update(self) -> Status:
        self.done += 1
        return Status.SUCCESS if self.done >= self.ports.require("ticks", int) else Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.IDLE:  # halted
            root = self.blackboard.root
            root.set("halts", f"{root.get('halts', '')}{self.name}")


@control(children=(2, None))
class Race(Control):
    """Ticks every child each tick; the first to succeed wins, and the others still RUNNING are halted, one by one."""

    def bt_tick(self) -> Status:
        self.set_bt_status(Status.RUNNING)
        for index in range(len(self.child_nodes)):
            if self.tick_child(index) is Status.SUCCESS:
                for other in range(len(self.child_nodes)):
                    if other != index and self.child_nodes[other].bt_state is Status.RUNNING:
                        self.halt_child(other)  # BT.CPP's haltChild(i)
                self.reset_children()  # the winner back to IDLE too
                return Status.SUCCESS
        return Status.RUNNING


def test_a_control_ticks_and_halts_one_child_with_public_calls() -> None:
    registry = builtin_registry()
    registry.register(Work)
    registry.register(Race)
    tree = load_tree_from_string(_tree('<Race><Work name="slow" ticks="5"/><Work name="fast" ticks="2"/>'
                                       '<Work name="slower" ticks="9"/></Race>'), registry)
    # tick 1: slow RUNNING, fast RUNNING, slower RUNNING -> RUNNING
    assert tree.tick() is R
    # tick 2: slow RUNNING, fast SUCCESS -> slow halted (slower was never ticked again? it was: RUNNING from
    # tick 1), slower halted -> SUCCESS; every child IDLE
    assert tree.tick() is S
    assert tree.root_blackboard.get("halts") == "slowslower"
    assert [tree.find(n).bt_state for n in ("slow", "fast", "slower")] == [Status.IDLE] * 3


def test_reset_children_halts_a_running_child_as_btcpp_410() -> None:
    @control()
    class StopAll(Control):
        """Ticks its first child once, then resets every child."""

        def __init__(self, ctx: NodeContext) -> None:
            super().__init__(ctx)
            self.started = False

        def bt_tick(self) -> Status:
            if not self.started:
                self.started = True
                self.set_bt_status(Status.RUNNING)
                return self.tick_child(0)
            self.reset_children()
            return Status.FAILURE

    registry = builtin_registry()
    registry.register(Work)
    registry.register(StopAll)
    tree = load_tree_from_string(_tree('<StopAll><Work name="w" ticks="3"/></StopAll>'), registry)
    assert tree.tick() is R  # tick 1: w RUNNING
    assert tree.tick() is F  # tick 2: reset_children() halts the RUNNING w (terminate(IDLE)), then FAILURE
    assert tree.root_blackboard.get("halts") == "w"


def test_the_old_private_call_names_the_public_one() -> None:
    @control()
    class Old(Control):
        def bt_tick(self) -> Status:
            return self._tick_child(0)

    registry = builtin_registry()
    registry.register(Old)
    tree = load_tree_from_string(_tree("<Old><AlwaysSuccess/></Old>"), registry)
    with pytest.raises(TreeRuntimeError, match=r"_tick_child\(i\) is now tick_child\(i\)"):
        tree.tick()


def test_the_api_table_names_every_public_name_and_what_controls_use() -> None:
    import bt_grasp.nodes as api

    page = (REPO / "docs" / "own-leaves.md").read_text()
    table = page.split("## The API (`bt_grasp.nodes`)", 1)[1].split("\n## ", 1)[0]
    missing = [name for name in api.__all__ if f"`{name}" not in table]
    assert missing == []
    for name in ("tick_child", "halt_child", "halt_children", "reset_children", "child_nodes", "bt_state",
                 "self.name", "register_simple_action", "register_simple_condition", "require", "has"):
        assert name in table, name
    reset_row = next(line for line in table.splitlines() if "reset_children" in line)
    assert "halt" in reset_row  # it halts RUNNING children too, as BT.CPP 4.10's resetChildren()


# ---- finding 5: registration --------------------------------------------------------------------------------


def test_simple_nodes_from_a_function_and_a_port_list() -> None:
    registry = builtin_registry()
    said: list[str] = []

    def say_hello(node: Leaf) -> Status:
        said.append(f"hello {node.ports.require('who', str)}")
        return Status.SUCCESS

    registry.register_simple_action("SayHello", say_hello, [input_port("who", str, "world")])
    registry.register_simple_condition(
        "BatteryOK", lambda node: S if node.ports.require("level", int) >= 20 else F,
        [input_port("level", int, "{battery}", "charge in percent")])
    tree = load_tree_from_string(_tree('<Sequence><BatteryOK/><SayHello who="dock"/></Sequence>'), registry)
    tree.root_blackboard.set("battery", 50)
    assert tree.tick() is S  # tick 1: BatteryOK SUCCESS (50), SayHello SUCCESS
    tree.root_blackboard.set("battery", 10)
    assert tree.tick() is F  # tick 2: BatteryOK FAILURE (10): SayHello not ticked
    assert said == ["hello dock"]
    assert registry["SayHello"].kind.value == "Action" and registry["BatteryOK"].kind.value == "Condition"


def test_a_simple_action_may_not_return_running_as_btcpp_sync_actions() -> None:
    registry = builtin_registry()
    registry.register_simple_action("Spin", lambda node: Status.RUNNING)
    tree = load_tree_from_string(_tree("<Spin/>"), registry)
    with pytest.raises(TreeRuntimeError, match="a simple action must never return RUNNING"):
        tree.tick()


def test_the_same_plugin_installed_and_given_with_leaves_names_who_registered_first(
    installed: list[FakeEntryPoint], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from bt_grasp.tree.plugins import load_file

    installed.append(FakeEntryPoint("weights", "user_nodes:register", load_file(PLUGIN).register, "weigh-dist"))
    tree = tmp_path / "t.xml"
    tree.write_text(_tree("<AlwaysSuccess/>"))
    assert main(["tree", "validate", "--leaves", str(PLUGIN), str(tree)]) == 2
    err = capsys.readouterr().err.strip()
    first = "entry point 'weights = user_nodes:register' of weigh-dist (group bt_grasp.leaves)"
    assert err.endswith(f"a failure reason named 'WEIGHT_OUT_OF_RANGE' is already registered by {first}")
    # --no-plugins leaves the installed one out: the same file alone is fine
    assert main(["tree", "validate", "--no-plugins", "--leaves", str(PLUGIN), str(tree)]) == 0


def test_a_node_declaring_a_reason_another_plugin_registered_first_is_named() -> None:
    registry = builtin_registry()
    with registry.registering("first.py"):
        registry.register_reason(Reason("TOO_HEAVY", "Heavier than allowed."))
    with registry.registering("second.py"), pytest.raises(DeclarationError, match=r"already registered by first\.py"):
        registry.register_reason(Reason("TOO_HEAVY", "Heavier than allowed."))


def test_models_of_the_plugins_alone_with_groot2_type_names(
    installed: list[FakeEntryPoint], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from bt_grasp.tree.plugins import load_file

    installed.append(FakeEntryPoint("weights", "user_nodes:register", load_file(PLUGIN).register, "weigh-dist"))
    typed = tmp_path / "typed.py"
    typed.write_text(TYPED_PLUGIN)
    assert main(["tree", "models", "--only-plugins", "--leaves", str(typed)]) == 0
    out = capsys.readouterr().out
    ids = re.findall(r' ID="(\w+)"', out)
    assert ids == ["CheckWeight", "Dock", "RateLimit", "RoundRobinFallback", "WaitSim"]  # no bt_grasp node
    assert '<input_port name="goal" type="PoseXY" />' in out.replace('"/>', '" />')
    assert '<output_port name="path" type="NavPath" />' in out.replace('"/>', '" />')
    assert '<input_port name="max_grams" type="double" default="500.000000">' in out
    # --plugin NAME loads only that installed plugin; --no-plugins none
    assert main(["tree", "models", "--only-plugins", "--plugin", "weigh-dist"]) == 0
    assert re.findall(r' ID="(\w+)"', capsys.readouterr().out) == ["CheckWeight", "RateLimit", "RoundRobinFallback",
                                                                    "WaitSim"]
    assert main(["tree", "models", "--only-plugins", "--no-plugins", "--leaves", str(typed)]) == 0
    assert re.findall(r' ID="(\w+)"', capsys.readouterr().out) == ["Dock"]
    assert main(["tree", "models", "--plugin", "nope"]) == 2
    assert capsys.readouterr().err.strip() == ("bt-grasp: error: --plugin: no installed plugin is called 'nope' "
                                               "(installed: weights)")


TYPED_PLUGIN = '''from dataclasses import dataclass

from bt_grasp.nodes import Leaf, Status, action, input_port, output_port


@dataclass
class PoseXY:
    x: float
    y: float

    @classmethod
    def from_port_text(cls, text: str) -> "PoseXY":
        x, y = text.split(";")
        return cls(float(x), float(y))


@dataclass
class NavPath:
    points: int


@action(ports=[input_port("goal", PoseXY), input_port("speed", float, 0.5), output_port("path", NavPath)])
class Dock(Leaf):
    def update(self) -> Status:
        return Status.SUCCESS


def register(registry):
    registry.register(Dock)
'''


def test_model_warnings_use_groot2_type_names(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    @action(ports=[input_port("speed", float, 0.5), output_port("path", object)])
    class Dock(Leaf):
        def update(self) -> Status:
            return Status.SUCCESS

    registry = builtin_registry()
    registry.register(Dock)
    xml = ('<root BTCPP_format="4"><TreeNodesModel><Action ID="Dock">\n'
           '<input_port name="speed" type="int"/></Action></TreeNodesModel>'
           '<BehaviorTree ID="Main"><Dock/></BehaviorTree></root>')
    with caplog.at_level(logging.WARNING):
        load_tree_from_string(xml, registry)
    assert "port 'speed' of Dock has type double, the model says int (BT.CPP ignores it)" in caplog.text


def test_a_declared_reason_comes_with_its_node_and_a_name_alone_must_be_registered() -> None:
    heavy = Reason("TOO_HEAVY", "Heavier than allowed.")

    @action(reasons=[heavy])
    class Weigh(Leaf):
        def update(self) -> Status:
            return self.fail(heavy, "1.2 kg")

    registry = builtin_registry()
    registry.register(Weigh)
    assert registry.reason("TOO_HEAVY") is heavy

    @action(reasons=["NOT_KNOWN"])
    class Guess(Leaf):
        def update(self) -> Status:
            return Status.SUCCESS

    with pytest.raises(DeclarationError, match="declares the failure reason 'NOT_KNOWN', which is not registered"):
        registry.register(Guess)


def test_a_node_class_is_registered_under_another_name_with_extra_arguments() -> None:
    @action(ports=[output_port("out", str)])
    class Echo(Leaf):
        def __init__(self, ctx: NodeContext, text: str) -> None:
            super().__init__(ctx)
            self.text = text

        def update(self) -> Status:
            self.ports.set("out", self.text)
            return Status.SUCCESS

    registry = NodeRegistry()
    registry.register(Echo, "Hello", args=("hello",))  # BT.CPP's registerNodeType<Echo>("Hello", "hello")
    tree = load_tree_from_string(_tree('<Hello out="{said}"/>'), registry)
    assert tree.tick() is S and tree.root_blackboard.get("said") == "hello"
