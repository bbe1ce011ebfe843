"""Pick by class with a detector that sees perfectly: what the learned-detector pipeline achieves after the network.

For each seed: the seed's settled table is drawn once (``World``) and each visible object's oriented box is taken
from the simulator's segmentation (``bt_grasp.sim.labelling``, the dataset command's labels: a benchmark tool,
reading the truth on purpose); a tiny ONNX model whose constant output is those boxes stands in for the network;
``trees/pick_class.xml`` (its ``model`` pointed at that stand-in) then picks the seed's target of ``bench pick
--detector learned`` (``bt_grasp.bench.pick.class_target``) by class, judged by physics on that object.

    python tools/pick_class_oracle_bench.py --seeds 20 [--first-seed 0] [--scene scenes/household.yaml]

A bound on what trained weights can reach (their own misses come on top), beside the geometric detector picking
the same targets by colour (``bt-grasp bench pick --detector learned --tree trees/pick_with_recovery.xml``).
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from collections import Counter
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]


def stand_in_model(path: Path, scene: Path, seed: int) -> Path:
    """A model whose output is every visible object's true oriented box on ``seed``'s table (score 0.9)."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    from bt_grasp.detector.dataset import dataset_classes, label_from_mask, object_class
    from bt_grasp.detector.letterbox import LetterboxGeometry
    from bt_grasp.detector.obb import regularize_rboxes
    from bt_grasp.sim.labelling import SegmentationCamera
    from bt_grasp.sim.world import World

    world = World.from_file(scene, seed)
    masks = SegmentationCamera(world).masks()
    classes = dataset_classes()
    frame = world.camera.capture()
    assert frame is not None
    geometry = LetterboxGeometry.of(frame.color.shape[:2], (320, 320))
    rows = []
    for placed in world.placed:
        spec = placed.spec
        class_id = classes.index(object_class(spec.shape, spec.mesh, scene, spec.name))
        label = label_from_mask(masks[spec.name], class_id, 60)
        if label is not None:
            (cx, cy), (w, h), angle = cv2.minAreaRect(label.corners_px.astype(np.float32))
            b = regularize_rboxes(np.array([[cx, cy, w, h, math.radians(angle)]]))[0]
            rows.append((geometry.to_input(b[:2]), b[2:4] * geometry.gain, b[4], class_id))
    out = np.zeros((1, 4 + len(classes) + 1, max(len(rows), 1)), dtype=np.float32)
    for a, (xy, wh, angle, class_id) in enumerate(rows):
        out[0, 0:2, a], out[0, 2:4, a], out[0, -1, a] = xy, wh, angle
        out[0, 4 + class_id, a] = 0.9
    nodes = [helper.make_node("ReduceMax", ["images"], ["peak"], keepdims=0),
             helper.make_node("Constant", [], ["zero"], value=numpy_helper.from_array(np.array(0.0, np.float32))),
             helper.make_node("Mul", ["peak", "zero"], ["nothing"]),
             helper.make_node("Constant", [], ["table"], value=numpy_helper.from_array(out)),
             helper.make_node("Add", ["table", "nothing"], ["output0"])]
    graph = helper.make_graph(nodes, "stand_in", [helper.make_tensor_value_info("images", TensorProto.FLOAT,
                                                                                [1, 3, 320, 320])],
                              [helper.make_tensor_value_info("output0", TensorProto.FLOAT, list(out.shape))])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    model.ir_version = 9
    helper.set_model_props(model, {"names": str(dict(enumerate(classes))), "task": "obb"})
    onnx.save(model, str(path))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--scene", type=Path, default=REPO / "scenes" / "household.yaml")
    args = parser.parse_args()
    from bt_grasp.bench.pick import class_target
    from bt_grasp.episode import pick_request, run_episode
    from bt_grasp.scene.goals import PickGoal

    work = Path(tempfile.mkdtemp(prefix="bt_grasp_oracle_"))
    text = (REPO / "trees" / "pick_class.xml").read_text()
    results: dict[int, str] = {}
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        name, class_name, color = class_target(args.scene, seed)
        model = stand_in_model(work / f"seed{seed}.onnx", args.scene, seed)
        tree = work / f"pick_class_{seed}.xml"
        tree.write_text(text.replace('detector="learned"', f'detector="learned" model="{model}"'))
        request = pick_request(tree, args.scene, seed, calibration=REPO / "scenes" / "tabletop.calibration.yaml")
        request = replace(request, goal=PickGoal(kind="pick", object=name),
                          blackboard={**request.blackboard, "class": class_name, "color": color})
        r = run_episode(request)
        failed = next((f"{c}: {d}" for c, m, d in r.judged.conditions if not m), "")
        results[seed] = f"picked {name}" if r.success else f"FAILURE {name}: {r.reason} ({r.failed_leaf}); {failed}"
        print(f"seed {seed}: {results[seed]}", flush=True)
    ok = sum(v.startswith("picked") for v in results.values())
    reasons = Counter(v.split(": ")[1].split(" (")[0] for v in results.values() if v.startswith("FAILURE"))
    print(json.dumps({"successes": ok, "runs": len(results), "failure_reasons": dict(reasons),
                      "runs_by_seed": results}))


if __name__ == "__main__":
    main()
