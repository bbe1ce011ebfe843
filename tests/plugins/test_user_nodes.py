"""Users' own nodes from a plugin file, tick by tick: a leaf with its own failure reason matched by FailureIs,
a sim-time wait, a control node (RoundRobinFallback) and a decorator (RateLimit), exactly as
tests/plugins/data/user_nodes.py (written only against bt_grasp.nodes) defines them."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from bt_grasp.clock import ManualClock
from bt_grasp.nodes import Leaf, NodeContext, Status, action
from bt_grasp.tree import LoadedTree, builtin_registry, load_tree_from_string
from bt_grasp.tree.kinds import NodeKind
from bt_grasp.tree.plugins import load_plugins

PLUGIN = Path(__file__).parent / "data" / "user_nodes.py"
S, F, R = "SUCCESS", "FAILURE", "RUNNING"
_PY = {S: Status.SUCCESS, F: Status.FAILURE, R: Status.RUNNING}


@dataclass
class Script:
    """What a stand-in leaf returns, tick after tick (the last one repeats), and what happened to it."""

    queue: list[str] = field(default_factory=lambda: [S])
    ticks: int = 0
    terminated: list[str] = field(default_factory=list)


@action(name="Stub")
class StandIn(Leaf):
    """Returns what its script says."""

    def __init__(self, ctx: NodeContext, run: Run) -> None:
        super().__init__(ctx)
        self.script, self.calls = run.scripts.setdefault(ctx.name, Script()), run.calls

    def update(self) -> Status:
        self.script.ticks += 1
        self.calls.append(self.name)
        queue = self.script.queue
        return _PY[queue.pop(0) if len(queue) > 1 else queue[0]]

    def terminate(self, new_status: Status) -> None:
        self.script.terminated.append(new_status.name)


class Run:
    """A tree of built-ins, ``Stub`` stand-ins and the plugin's nodes, on a simulated clock 10 ms a tick."""

    def __init__(self, body: str, **scripts: list[str]) -> None:
        self.scripts = {name: Script(list(q)) for name, q in scripts.items()}
        self.calls: list[str] = []
        registry = builtin_registry()
        registry.register(StandIn, args=(self,))
        load_plugins(registry, [str(PLUGIN)], installed=False)
        self.registry = registry
        self.clock = ManualClock()
        xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'
        self.tree: LoadedTree = load_tree_from_string(xml, registry, clock=self.clock)

    def tick(self) -> tuple[str, list[str]]:
        """The root's status and the stand-ins ticked, in order; then 10 ms of simulated time pass."""
        self.calls.clear()
        status = self.tree.tick().value
        self.clock.advance_s(0.010)
        return status, list(self.calls)


def test_the_plugin_registers_through_the_same_factory_as_the_builtins() -> None:
    run = Run("<AlwaysSuccess/>")
    specs = {name: run.registry[name] for name in ("CheckWeight", "WaitSim", "RoundRobinFallback", "RateLimit")}
    assert {n: s.kind for n, s in specs.items()} == {
        "CheckWeight": NodeKind.CONDITION, "WaitSim": NodeKind.ACTION,
        "RoundRobinFallback": NodeKind.CONTROL, "RateLimit": NodeKind.DECORATOR,
    }
    assert specs["CheckWeight"].port("max_grams").default == 500.0  # type: ignore[union-attr]
    assert specs["CheckWeight"].description == "SUCCESS when the weight is at most max_grams."
    assert run.registry.origins["RateLimit"] == str(PLUGIN)
    reason = run.registry.reason("WEIGHT_OUT_OF_RANGE")
    assert reason is not None and reason.description == "The weighed object is heavier than allowed."
    assert run.registry.reason_origins == {"WEIGHT_OUT_OF_RANGE": str(PLUGIN)}


def test_user_leaf_fails_with_its_own_reason_and_failure_is_matches_it() -> None:
    run = Run("""<Sequence>
      <Fallback>
        <CheckWeight grams="750"/>
        <Sequence>
          <FailureIs reason="WEIGHT_OUT_OF_RANGE" leaf="CheckWeight"/><Script code="verdict := 'rejected'"/>
        </Sequence>
      </Fallback>
      <WaitSim seconds="0.03"/>
    </Sequence>""")
    # tick 1 (t=0): CheckWeight FAILURE (750 g > 500 g), FailureIs SUCCESS, Script: the Fallback succeeds;
    #               WaitSim starts, its deadline is t=30 ms: RUNNING
    # ticks 2, 3 (t=10, 20 ms): WaitSim RUNNING; tick 4 (t=30 ms): SUCCESS
    assert run.tick()[0] == R
    bb = run.tree.root_blackboard.items()  # during the run, the leaf's failure is on the blackboard
    assert bb["failure_reason"] == "WEIGHT_OUT_OF_RANGE" and bb["failed_leaf"] == "CheckWeight"
    assert [run.tick()[0] for _ in range(3)] == [R, R, S]
    bb = run.tree.root_blackboard.items()
    assert bb["verdict"] == "rejected"
    assert "failure_reason" not in bb and "failed_leaf" not in bb  # the tree succeeded: cleared
    node = run.tree.find("CheckWeight")
    assert node.feedback_message == "750 g is more than 500 g"


def test_failure_is_does_not_match_another_reason() -> None:
    run = Run("""<Fallback>
      <CheckWeight grams="750"/>
      <FailureIs reason="SLIPPED"/>
    </Fallback>""")
    assert run.tick()[0] == F  # the reason was WEIGHT_OUT_OF_RANGE, not SLIPPED


def test_round_robin_fallback_tick_by_tick() -> None:
    run = Run(
        "<RoundRobinFallback><Stub name='A'/><Stub name='B'/><Stub name='C'/></RoundRobinFallback>",
        A=[F], B=[R, S, S, F], C=[S, F],
    )
    expected = [
        (R, ["A", "B"]),  # start at A: A fails, B runs
        (S, ["B"]),  # B resumed: succeeds; the next activation starts at C
        (S, ["C"]),  # C succeeds; next start wraps to A
        (S, ["A", "B"]),  # A fails, B succeeds; next start C
        (F, ["C", "A", "B"]),  # C, A and B all fail, each once: FAILURE; the start stays at C
        (F, ["C", "A", "B"]),
    ]
    assert [run.tick() for _ in expected] == expected
    assert run.scripts["B"].terminated == ["SUCCESS", "SUCCESS", "FAILURE", "FAILURE"]


def test_round_robin_fallback_halts_its_running_child() -> None:
    run = Run(
        """<ReactiveSequence>
             <ScriptCondition code="go"/>
             <RoundRobinFallback><Stub name='A'/><Stub name='B'/></RoundRobinFallback>
           </ReactiveSequence>""",
        A=[R],
    )
    run.tree.root_blackboard.set("go", True)
    assert run.tick() == (R, ["A"])
    run.tree.root_blackboard.set("go", False)
    assert run.tick() == (F, [])  # the condition fails: the ReactiveSequence halts the RUNNING A
    assert run.scripts["A"].terminated == ["IDLE"]
    assert run.tree.find("A").bt_state.value == "IDLE"


def test_rate_limit_counts_simulated_time_tick_by_tick() -> None:
    run = Run("<RateLimit period_msec='30'><Stub name='A'/></RateLimit>", A=[S, S, R, R, S, S])
    expected = [
        (S, ["A"]),  # t=0: A runs (its first start), succeeds
        (F, []),  # t=10: 10 ms since A started: rate limited, A is not ticked
        (F, []),  # t=20
        (S, ["A"]),  # t=30: 30 ms since the last start: A runs again
        (F, []),  # t=40
        (F, []),  # t=50
        (R, ["A"]),  # t=60: A starts and is RUNNING
        (R, ["A"]),  # t=70: a RUNNING child is always ticked
        (S, ["A"]),  # t=80: it succeeds
        (S, ["A"]),  # t=90: 30 ms since it started at t=60: allowed again
        (F, []),  # t=100
    ]
    assert [run.tick() for _ in expected] == expected
    assert run.scripts["A"].ticks == 6
