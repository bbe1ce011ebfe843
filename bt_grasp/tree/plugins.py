"""Users' own nodes: plugins that register leaves, controls, decorators and failure reasons.

A plugin is Python code with a ``register(registry)`` function (BT.CPP's ``BT_REGISTER_NODES``): it registers
through the same :class:`~bt_grasp.tree.registry.NodeRegistry` as the built-ins, so nothing downstream (the
loader, ``tree models``, the runner, recording, replay) can tell them apart. Plugins come from

* a file or module named on the command line (``--leaves my_leaves.py`` or ``--leaves my_pkg.nodes``,
  repeatable): user code the user chose to run, trusted like the user's own Python;
* an installed distribution's entry point in the group ``bt_grasp.leaves``
  (``[project.entry-points."bt_grasp.leaves"] my_nodes = "my_pkg.nodes:register"``), discovered once per
  process with :func:`importlib.metadata.entry_points`.

Installed plugins are all loaded unless a command says otherwise (``--no-plugins``: none of them; ``--plugin
NAME``: only those named, by entry point or distribution name). Anything wrong with a plugin (it cannot be
imported, it has no ``register``, it registers a name that exists, it declares a bad port or reason) raises
:class:`PluginError`: exit 2, one sentence naming the file (or the distribution and entry point) and the problem;
a name registered twice also names the plugin that registered it first.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import importlib.util
import sys
import traceback
import zlib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType

from bt_grasp.errors import InputError
from bt_grasp.tree.exceptions import DeclarationError
from bt_grasp.tree.registry import NodeRegistry

#: the entry point group installed packages declare their ``register`` function in
ENTRY_POINT_GROUP = "bt_grasp.leaves"

RegisterHook = Callable[[NodeRegistry], object]


class PluginError(InputError):
    """A plugin could not be loaded or registered a bad node (exit 2, one sentence)."""


@dataclass(frozen=True)
class Plugin:
    """A loaded plugin: where it came from (shown in errors and as the origin of its nodes) and its hook."""

    source: str
    register: RegisterHook
    #: the file the plugin's code is in, for a line number in errors ("" when unknown)
    path: str = ""
    #: the names it answers to in ``--plugin NAME``: an installed one's entry point and distribution names
    names: tuple[str, ...] = ()


def _is_file_name(spec: str) -> bool:
    return spec.endswith(".py") or "/" in spec or "\\" in spec or Path(spec).exists()


def _error_line(exc: BaseException, path: str) -> int | None:
    """The last line of ``path`` in the exception's traceback (where the plugin's own code went wrong)."""
    if isinstance(exc, SyntaxError) and exc.filename == path:
        return exc.lineno
    line = None
    for frame in traceback.extract_tb(exc.__traceback__):
        if frame.filename == path:
            line = frame.lineno
    return line


def _describe(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if isinstance(exc, SyntaxError):
        return f"syntax error: {exc.msg}"
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _import_problem(exc: BaseException) -> str:
    if isinstance(exc, DeclarationError):  # a node, port or reason declared at import (``@action(ports=...)``)
        return f"bad declaration: {str(exc).strip().splitlines()[0]}"
    return f"import error: {_describe(exc)}"


def _register_problem(exc: BaseException) -> str:
    if isinstance(exc, DeclarationError):  # a duplicate name, a bad spec handed to the registry
        return f"bad declaration: {str(exc).strip().splitlines()[0]}"
    return f"register() failed: {_describe(exc)}"


def _hook_of(module: ModuleType, source: str, path: str) -> Plugin:
    hook = getattr(module, "register", None)
    if not callable(hook):
        raise PluginError(source, "defines no register(registry) function (see docs/own-leaves.md)")
    return Plugin(source, hook, path)


def load_file(path: str | Path) -> Plugin:
    """Import a plugin file (a fresh module each time) and return its ``register`` hook."""
    file = Path(path)
    source = str(path)
    if not file.is_file():
        raise PluginError(source, "no such plugin file" if not file.exists() else "is not a file")
    if file.suffix != ".py":
        raise PluginError(source, "a plugin file must be Python source ending in .py")
    resolved = str(file.resolve())
    module_name = f"bt_grasp_user_leaves.{file.stem}_{zlib.crc32(resolved.encode()):08x}"
    spec = importlib.util.spec_from_file_location(module_name, resolved)
    if spec is None or spec.loader is None:  # pragma: no cover - a .py file always has a loader
        raise PluginError(source, "cannot be imported")
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's code: any error is a one-sentence answer, never a traceback
        sys.modules.pop(module_name, None)
        raise PluginError(source, _import_problem(exc), where=_error_line(exc, resolved)) from None
    return _hook_of(module, source, resolved)


def load_module(name: str) -> Plugin:
    """Import a plugin module by its dotted name and return its ``register`` hook."""
    if not all(part.isidentifier() for part in name.split(".")):
        raise PluginError(name, "is neither a .py file nor a module name such as my_pkg.nodes")
    try:
        module = importlib.import_module(name)
    except Exception as exc:
        raise PluginError(name, _import_problem(exc)) from None
    return _hook_of(module, name, str(getattr(module, "__file__", "") or ""))


def load_spec(spec: str) -> Plugin:
    """``--leaves`` value: a ``.py`` file (or any existing path) or a module name."""
    spec = spec.strip()
    if not spec:
        raise PluginError("--leaves", "an empty plugin name")
    return load_file(spec) if _is_file_name(spec) else load_module(spec)


@functools.cache
def entry_point_plugins() -> tuple[Plugin, ...]:
    """The ``bt_grasp.leaves`` entry points of installed distributions, loaded once per process (sorted by
    distribution and name, so the order of registration is the same on every machine)."""
    found = sorted(
        entry_points(group=ENTRY_POINT_GROUP),
        key=lambda ep: (ep.dist.name if ep.dist is not None else "", ep.name),
    )
    plugins = []
    for ep in found:
        dist = ep.dist.name if ep.dist is not None else "an unknown distribution"
        source = f"entry point '{ep.name} = {ep.value}' of {dist} (group {ENTRY_POINT_GROUP})"
        try:
            target = ep.load()
        except Exception as exc:
            raise PluginError(source, _import_problem(exc)) from None
        # no line numbers for these: the source named in errors is the entry point, not a file
        names = (ep.name, dist)
        if isinstance(target, ModuleType):
            plugins.append(dataclasses.replace(_hook_of(target, source, ""), names=names))
        elif callable(target):
            plugins.append(Plugin(source, target, names=names))
        else:
            raise PluginError(source, f"names {target!r}, neither a register(registry) function nor a module")
    return tuple(plugins)


def apply(registry: NodeRegistry, plugins: Iterable[Plugin]) -> NodeRegistry:
    """Run each plugin's ``register(registry)``; a failing one raises PluginError naming it. The registry
    records the plugin as the origin of every node and reason it registers."""
    for plugin in plugins:
        try:
            with registry.registering(plugin.source):
                plugin.register(registry)
        except Exception as exc:  # DeclarationError (duplicate, bad port), or any error of the user's code
            where = _error_line(exc, plugin.path) if plugin.path else None
            raise PluginError(plugin.source, _register_problem(exc), where=where) from None
    return registry


#: which installed plugins a command loads: all (True), none (False), or those named (entry point or distribution)
Installed = bool | Sequence[str]


def installed_plugins(chosen: Installed = True) -> tuple[Plugin, ...]:
    """The installed plugins a command loads: every one, none, or the ones named (``--plugin NAME``: an entry
    point's or a distribution's name); a name no installed plugin has raises PluginError listing theirs."""
    if chosen is True:
        return entry_point_plugins()
    if chosen is False or not chosen:
        return ()
    found = entry_point_plugins()
    for name in chosen:
        if not any(name in plugin.names for plugin in found):
            listing = ", ".join(sorted({p.names[0] for p in found if p.names})) or "none is installed"
            raise PluginError("--plugin", f"no installed plugin is called '{name}' (installed: {listing})")
    return tuple(plugin for plugin in found if set(plugin.names) & set(chosen))


def load_plugins(registry: NodeRegistry, leaves: Sequence[str] = (), installed: Installed = True) -> NodeRegistry:
    """Add the installed plugins (entry points: all of them, none, or those named, see
    :func:`installed_plugins`) and then each ``--leaves`` file or module, in order, to ``registry``. Raises
    PluginError (exit 2) naming the plugin and the problem."""
    plugins: list[Plugin] = list(installed_plugins(installed))
    plugins += [load_spec(spec) for spec in leaves]
    return apply(registry, plugins)
