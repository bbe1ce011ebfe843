"""Print where bt_grasp and the recorded BT.CPP run of corpus trees differ:
``python -m tests.tree_conformance.show_diff NAME ...`` (for investigating a failing corpus test)."""

from __future__ import annotations

import json
import sys

from .test_corpus import CORPUS, TICKED, directives
from .twin import run_tree


def main(names: list[str]) -> int:
    for name in names:
        tree = CORPUS / f"{name}.xml"
        expected = json.loads(tree.with_suffix(".btcpp.json").read_text())
        options = directives(tree.read_text())
        got = run_tree(tree.resolve(), int(options.get("max_ticks", 20)), int(options.get("period_ms", 0)))
        fields = ("status", "blackboard", "error") + (() if options.get("compare") == "final" else TICKED)
        print(f"== {name}")
        for key in fields:
            if got.get(key) != expected.get(key):
                print(f"  {key}:\n    bt_grasp: {json.dumps(got.get(key))}")
                print(f"    btcpp:    {json.dumps(expected.get(key))}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
