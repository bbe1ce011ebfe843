"""`bt-grasp run ... --interactive`: a terminal front end (Textual) over :class:`bt_grasp.control.Controller`.

It draws the tree with live statuses, the blackboard (entries a port reads, which may be set, are marked
``*``), the current detections, the last failure and the run's state, and sends commands on keys:

====  =============================================================================================
p     pause / continue
s     step one tick
n     step N ticks (asks N)
f     break on a leaf FAILURE (``--break fail``: not the conditions false by design): on / off
b     set a blackboard entry (asks ``KEY=VALUE``; the value is checked against the ports reading it)
o     choose the object to act on (asks ``INDEX|LABEL [ENTRY]``; ENTRY defaults to ``target``)
x     fire a fault of the catalogue now (asks ``KIND [KEY=VALUE,...]``)
r, R  restart the episode with the same seed / the next seed (a new log: ``run-2.mcap``, ...)
q     quit: the run stops at the next tick boundary, its log is finished
====  =============================================================================================

The episode runs in a worker thread; the UI only reads :meth:`Controller.state` and sends commands. The run
starts paused before its first tick (``p`` runs it). This module composes nothing: it receives a
:class:`Session` saying how to run one episode with a controller.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

from rich.markup import escape
from rich.text import Text
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.widgets import Input, Static

from bt_grasp.control import (
    Breakpoint,
    ChooseObject,
    ClearBreakpoint,
    Command,
    Controller,
    FireFault,
    Pause,
    Restart,
    Resume,
    RunState,
    SeedPolicy,
    SetBlackboard,
    SetBreakpoint,
    Source,
    Step,
    Stop,
    parse_breakpoint,
)

KEYS_HELP = ("p pause/continue  s step  n step N  f break on failure  b set entry  o choose object  "
             "x fire fault  r/R restart (same/next seed)  q quit")
STATUS_STYLE = {"RUNNING": "yellow", "SUCCESS": "green", "FAILURE": "bold red", "IDLE": "dim", "SKIPPED": "dim"}
_FAIL = parse_breakpoint("fail")


@dataclass
class Session:
    """What the UI drives. ``run_one(controller, seed, number)`` runs episode ``number`` (0, 1, ... after
    restarts) with ``seed`` under ``controller``, blocking, and returns a one-line summary."""

    run_one: Callable[[Controller, int, int], str]
    seed: int
    breakpoints: tuple[Breakpoint, ...] = ()
    start_paused: bool = True


@dataclass(frozen=True)
class _Prompt:
    key: str
    question: str


PROMPTS = {
    "n": _Prompt("n", "ticks to step (then Enter; Esc cancels)"),
    "b": _Prompt("b", "KEY=VALUE to set on the blackboard"),
    "o": _Prompt("o", "object INDEX or LABEL, then the ENTRY to write (default target)"),
    "x": _Prompt("x", "fault KIND and KEY=VALUE,... parameters, e.g. frame_drop frames=2"),
}


def parse_prompt(key: str, text: str) -> Command:
    """The command an answer to prompt ``key`` asks for; ValueError with one sentence when it cannot be read."""
    text = text.strip()
    if key == "n":
        try:
            n = int(text)
        except ValueError:
            raise ValueError(f"'{text}' is not a number of ticks") from None
        if n < 1:
            raise ValueError("step at least 1 tick")
        return Step(n)
    if key == "b":
        name, sep, value = text.partition("=")
        if not sep or not name.strip():
            raise ValueError(f"expected KEY=VALUE, got '{text}'")
        return SetBlackboard(name.strip(), value.strip())
    if key == "o":
        parts = text.split()
        if not parts or len(parts) > 2:
            raise ValueError(f"expected INDEX|LABEL [ENTRY], got '{text}'")
        choice: int | str = int(parts[0]) if parts[0].isdigit() else parts[0]
        return ChooseObject(choice, parts[1] if len(parts) == 2 else "target")
    if key == "x":
        kind, _, rest = text.partition(" ")
        if not kind:
            raise ValueError("name a fault kind, e.g. frame_drop")
        return FireFault(kind, _params(rest))
    raise ValueError(f"no prompt '{key}'")


def _params(text: str) -> dict[str, object]:
    from bt_grasp.files.bounded_yaml import load_value

    params: dict[str, object] = {}
    for item in (i.strip() for i in text.replace(",", " ").split()):
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise ValueError(f"expected KEY=VALUE, got '{item}'")
        try:
            params[name] = load_value(value)
        except ValueError:
            params[name] = value
    return params


def tree_text(state: RunState) -> Text:
    text = Text()
    for node in state.nodes:
        label = node.name if node.name == node.type else f"{node.name} ({node.type})"
        text.append("  " * node.depth + label + "  ")
        text.append(node.status, style=STATUS_STYLE.get(node.status, ""))
        text.append("\n")
    return text


def failure_text(state: RunState) -> str:
    """The "last failure" panel: the last leaf FAILURE that was not false by design (those ``replay --failures``
    sets apart: a condition a Fallback asked), its path, its reason and what the leaf said."""
    failure = state.last_failure
    if failure is None:
        return "none (conditions false by design are not listed)"
    said = f"\n{failure.message}" if failure.message else ""
    return f"tick {failure.tick}: {failure.path or failure.leaf}\nreason: {failure.reason or 'none given'}{said}"


def status_line(state: RunState, number: int) -> str:
    if state.finished:
        what = "FINISHED"
    elif state.paused:
        what = f"PAUSED: {state.pause_reason}"
    else:
        what = "running"
    episode = f"episode {number + 1}  " if number else ""
    return (f"{episode}tick {state.tick}  t={state.sim_time_s:.3f} s  tree {state.tree_status}  {what}  |  "
            f"break on failure: {'on' if state.break_on_failure else 'off'}  |  "
            f"interventions: {len(state.interventions)}")


class InteractiveApp(App[None]):
    """The terminal front end. ``run()`` returns when the user quits after the last episode ended."""

    CSS = """
    #status { height: 1; background: $boost; }
    #message { height: 1; color: $warning; }
    #keys { height: 1; color: $text-muted; }
    #panes { height: 1fr; }
    #tree { width: 1fr; border: round $primary; }
    #side { width: 1fr; }
    #blackboard { height: 1fr; border: round $primary; text-wrap: nowrap; text-overflow: ellipsis; }
    #detections { height: auto; max-height: 8; border: round $primary; }
    #failure { height: auto; border: round $primary; }
    #prompt { display: none; }
    #prompt.asking { display: block; }
    """
    AUTO_FOCUS = None  # keys go to the app; the prompt takes focus only while it asks
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("p", "toggle_pause", "pause/continue"),
        Binding("s", "step", "step"),
        Binding("f", "toggle_fail", "break on failure"),
        Binding("n", "ask('n')", "step N"),
        Binding("b", "ask('b')", "set entry"),
        Binding("o", "ask('o')", "choose object"),
        Binding("x", "ask('x')", "fire fault"),
        Binding("r", "restart('same')", "restart"),
        Binding("R", "restart('next')", "restart next seed"),
        Binding("q", "quit_run", "quit"),
        Binding("escape", "cancel", "cancel", show=False),
    ]

    def __init__(self, session: Session, refresh_s: float = 0.1) -> None:
        super().__init__()
        self.session = session
        self.refresh_s = refresh_s
        self.controller = Controller(session.breakpoints, start_paused=session.start_paused)
        self.number = 0
        self.summaries: list[str] = []
        self.error: BaseException | None = None
        self.done = threading.Event()
        self._quitting = False
        self._asking: str | None = None
        self._note = ""
        self._shown: tuple[RunState, int, str, bool] | None = None
        self._worker = threading.Thread(target=self._episodes, name="bt_grasp-episode", daemon=True)

    # ---- layout -------------------------------------------------------------------------------------------
    def compose(self) -> ComposeResult:
        yield Static("", id="status")
        with Horizontal(id="panes"):
            yield Static("", id="tree")
            with Vertical(id="side"):
                yield Static("", id="blackboard")
                yield Static("", id="detections")
                yield Static("", id="failure")
        yield Static("", id="message")
        yield Input(id="prompt", disabled=True)  # enabled (and focusable) only while it asks
        yield Static(KEYS_HELP, id="keys")

    def on_mount(self) -> None:
        for pane, title in (("tree", "tree"), ("blackboard", "blackboard (* may be set: b)"),
                            ("detections", "detections (o chooses)"), ("failure", "last failure")):
            self.query_one(f"#{pane}", Static).border_title = title
        self._worker.start()
        self.set_interval(self.refresh_s, self.show)
        self.show()

    def show(self) -> None:
        """Redraw from the controller's latest state (nothing to do when it did not change)."""
        state = self.controller.state()
        key = (state, self.number, self._note, self.done.is_set())
        if key == self._shown:
            return
        self._shown = key
        self.query_one("#status", Static).update(escape(status_line(state, self.number)))
        self.query_one("#tree", Static).update(tree_text(state))
        settable = set(state.settings)
        self.query_one("#blackboard", Static).update(Text("\n".join(
            f"{'*' if key in settable else ' '} {key} = {value}" for key, value in state.blackboard),
            no_wrap=True, overflow="ellipsis"))  # one line an entry
        self.query_one("#detections", Static).update(Text("\n".join(
            f"{d.index}: {d.label} at ({', '.join(f'{x:.3f}' for x in d.centroid_base_m)}) m"
            for d in state.detections) or "none yet"))
        self.query_one("#failure", Static).update(Text(failure_text(state)))
        message = self._note or state.message
        if self.done.is_set():
            message = ("finished: " + "; ".join(self.summaries[-1:]) if self.error is None
                       else f"the run ended with an error: {self.error}") + "  (q exits)"
        self.query_one("#message", Static).update(Text(message))

    # ---- keys ---------------------------------------------------------------------------------------------
    def _send(self, command: Command) -> None:
        self._note = ""
        self.controller.send(command, Source.TERMINAL)

    def action_toggle_pause(self) -> None:
        self._send(Resume() if self.controller.state().paused else Pause())

    def action_step(self) -> None:
        self._send(Step(1))

    def action_toggle_fail(self) -> None:
        on = self.controller.state().break_on_failure
        self._send(ClearBreakpoint(_FAIL) if on else SetBreakpoint(_FAIL))

    def action_restart(self, seed: str) -> None:
        self._send(Restart(SeedPolicy(seed)))

    def action_ask(self, key: str) -> None:
        prompt = self.query_one("#prompt", Input)
        self._asking = key
        prompt.placeholder = PROMPTS[key].question
        prompt.value = ""
        prompt.disabled = False
        prompt.add_class("asking")
        prompt.focus()

    def action_cancel(self) -> None:
        self._close_prompt()

    def _close_prompt(self) -> None:
        prompt = self.query_one("#prompt", Input)
        prompt.remove_class("asking")
        prompt.disabled = True  # keys go to the app again, never into a hidden prompt
        self._asking = None
        self.set_focus(None)

    def on_input_submitted(self, event: Input.Submitted) -> None:
        key = self._asking
        self._close_prompt()
        if key is None:
            return
        try:
            command = parse_prompt(key, event.value)
        except ValueError as exc:
            self._note = str(exc)
            self.show()
            return
        self._send(command)

    def action_quit_run(self) -> None:
        if self.done.is_set():
            self.exit()
            return
        self._quitting = True
        self._send(Stop())

    # ---- the episodes -------------------------------------------------------------------------------------
    def _episodes(self) -> None:
        seed = self.session.seed
        try:
            while True:
                self.summaries.append(self.session.run_one(self.controller, seed, self.number))
                restart = self.controller.restart
                if restart is None:
                    break
                breakpoints = tuple(parse_breakpoint(s) for s in self.controller.state().breakpoints)
                seed += 1 if restart is SeedPolicy.NEXT else 0
                self.number += 1
                self.controller = Controller(breakpoints, start_paused=self.session.start_paused)
        except BaseException as exc:  # shown, then raised again by the caller once the terminal is restored
            self.error = exc
        finally:
            self.done.set()
            if self._quitting:
                self.call_from_thread(self.exit)

    def stop_and_wait(self, timeout_s: float = 60.0) -> None:
        """After the app ended (any way): stop a run still going and wait for its log to be finished."""
        if self._worker.is_alive():
            self.controller.send(Stop(), Source.TERMINAL)
            self._worker.join(timeout_s)
