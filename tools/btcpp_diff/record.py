"""Re-record the differential corpus with BehaviorTree.CPP itself.

Given an already-built BehaviorTree.CPP 4.10 (its include folder and the folder holding
``libbehaviortree_cpp.a`` or ``.so``; the bundled tinyxml2/minitrace archives are looked for below it), this
compiles ``driver.cpp`` (bt_grasp's own driver) with ``g++``, runs every tree of the corpus through it and
writes ``NAME.btcpp.json`` next to ``NAME.xml``. The tests then compare bt_grasp against those files, so CI
needs no C++ build. This tool does not build BehaviorTree.CPP: build it yourself from its 4.10.0 source.

    python tools/btcpp_diff/record.py --include /path/to/BehaviorTree.CPP/include \\
        --lib /path/to/BehaviorTree.CPP/build [--corpus tests/tree_conformance/corpus] [--only NAME ...]

A tree may start with a directive comment: ``<!-- btcpp_diff: max_ticks=6 period_ms=10 compare=final -->``
(``period_ms`` sleeps between ticks so BT.CPP's wall-clock timers can fire; ``compare=final`` compares only
the final status and blackboard, for trees whose tick count depends on BT.CPP's wall clock).

``--cases tests/tree_conformance/rules`` records the substitution-rule cases instead: each ``NAME.xml`` there runs
with BT.CPP's ``loadSubstitutionRuleFromJSON`` of ``NAME.rules.json``, a stand-in registered for every action and
condition its TreeNodesModel declares (read by bt_grasp's own model reader, so both sides type the ports alike),
and the directives ``nodes_model=FILE`` (another TreeNodesModel, relative to the tree), ``set=KEY=VALUE,...``
(blackboard entries before the first tick), ``nav2=1`` (Nav2's controls instead of the stand-ins of
standins.hpp) and ``compare=order`` (BT.CPP's delays are wall-clock: only the order of the transitions counts).
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEFAULT_CORPUS = HERE.parents[1] / "tests" / "tree_conformance" / "corpus"
DIRECTIVE = re.compile(r"<!--\s*btcpp_diff:(?P<body>[^>]*)-->")


def directives(text: str) -> dict[str, str]:
    """The ``key=value`` pairs of a tree's ``btcpp_diff`` comment (empty when there is none)."""
    match = DIRECTIVE.search(text)
    if match is None:
        return {}
    return dict(part.split("=", 1) for part in match.group("body").split())


def _archives(lib_dir: Path) -> list[str]:
    main = [lib_dir / "libbehaviortree_cpp.a", lib_dir / "libbehaviortree_cpp.so"]
    found = [p for p in main if p.exists()]
    if not found:
        raise SystemExit(f"record.py: no libbehaviortree_cpp.a or .so in {lib_dir}")
    extra = sorted(str(p) for name in ("libtinyxml2.a", "libminitrace.a") for p in lib_dir.rglob(name))
    return [str(found[0]), *extra]


def compile_driver(include: Path, lib_dir: Path, out: Path) -> Path:
    compiler = shutil.which("g++") or shutil.which("c++")
    if compiler is None:
        raise SystemExit("record.py: no C++ compiler (g++) found")
    binary = out / "btcpp_diff_driver"
    command = [compiler, "-std=c++17", "-O1", f"-I{include}", str(HERE / "driver.cpp"), *_archives(lib_dir)]
    command += [f"-Wl,-rpath,{lib_dir}", "-lpthread", "-ldl", "-o", str(binary)]
    subprocess.run(command, check=True)
    return binary


def models_json(tree: Path, options: dict[str, str]) -> list[dict[str, object]]:
    """The actions and conditions of the tree's TreeNodesModel (and ``nodes_model``'s), as the driver's
    ``--models`` reads them, typed by bt_grasp's own reading of a model."""
    from bt_grasp.tree.loader import read_tree_file
    from bt_grasp.tree.model_stand_ins import model_specs, read_nodes_model

    models = list(read_tree_file(tree).models)
    if "nodes_model" in options:
        models += read_nodes_model(tree.parent / options["nodes_model"])
    names = {int: "int", float: "double", bool: "bool", str: "string"}
    return [
        {"kind": spec.kind.value.capitalize(), "id": spec.name,
         "ports": [{"name": p.name, "direction": p.direction.value, "type": names.get(p.type, "any"),
                    "default": p.default if p.has_default and isinstance(p.default, str) else None}
                   for p in spec.ports]}
        for spec, _ in model_specs(models, lambda name: False, None)
    ]


def rule_case_arguments(tree: Path, options: dict[str, str], scratch: Path) -> list[str]:
    """The driver's arguments for a substitution-rule case (see the module)."""
    models = scratch / f"{tree.stem}.models.json"
    models.write_text(json.dumps(models_json(tree, options)), encoding="utf-8")
    command = ["--rules", str(tree.with_suffix(".rules.json").resolve()), "--models", str(models)]
    for item in filter(None, options.get("set", "").split(",")):
        command += ["--set", item]
    if options.get("nav2") == "1":
        command.append("--nav2")
    return command


def record_one(binary: Path, tree: Path, scratch: Path | None = None) -> dict[str, object]:
    options = directives(tree.read_text(encoding="utf-8"))
    command = [str(binary), str(tree.resolve())]
    if "max_ticks" in options:
        command += ["--max-ticks", options["max_ticks"]]
    if "period_ms" in options:
        command += ["--period-ms", options["period_ms"]]
    if tree.with_suffix(".rules.json").exists():
        command += rule_case_arguments(tree, options, scratch or tree.parent)
    done = subprocess.run(command, check=True, capture_output=True, text=True, timeout=60)
    # BT.CPP prints a blackboard dump to stdout before some load errors: the JSON is the last line
    result: dict[str, object] = json.loads(done.stdout.strip().splitlines()[-1])
    result["tree"] = tree.name
    return result


def dumps(result: dict[str, object]) -> str:
    """The recording as JSON: one key per line, each transition on a line of its own (they are many)."""
    rest = {k: v for k, v in result.items() if k != "transitions"}
    text = json.dumps(rest, indent=1, sort_keys=True)
    moves = result.get("transitions")
    if not isinstance(moves, list):
        return text + "\n"
    lines = ",\n".join(f"  {json.dumps(move)}" for move in moves)
    body = f'"transitions": [\n{lines}\n ]' if moves else '"transitions": []'
    return text[:-2] + f",\n {body}\n}}\n"


def corpus_trees(corpus: Path) -> list[Path]:
    """Every tree of the corpus (files in ``lib/`` are included by others, not run on their own)."""
    return sorted(corpus.glob("*.xml"))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--include", type=Path, required=True, help="BehaviorTree.CPP's include folder")
    parser.add_argument("--lib", type=Path, required=True, help="the folder holding libbehaviortree_cpp")
    parser.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS)
    parser.add_argument("--cases", type=Path, default=None, help="record the substitution-rule cases of this folder "
                        "(tests/tree_conformance/rules) instead of the corpus")
    parser.add_argument("--only", nargs="*", default=None, help="tree names (without .xml) to re-record")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        binary = compile_driver(args.include, args.lib, Path(tmp))
        trees = corpus_trees(args.cases or args.corpus)
        if args.only:
            trees = [t for t in trees if t.stem in set(args.only)]
        for tree in trees:
            result = record_one(binary, tree, Path(tmp))
            if directives(tree.read_text(encoding="utf-8")).get("compare") == "final":
                result.pop("transitions", None)  # BT.CPP's wall clock decides them: never compared
            target = tree.with_suffix(".btcpp.json")
            target.write_text(dumps(result), encoding="utf-8")
            print(f"{tree.name}: {result['status']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
