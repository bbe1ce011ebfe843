"""One seed path (issue 37): every random draw of a run comes from a stream of the run's seed (``bt_grasp.seeds``).

Two seeds give different grasp samples, plans and calibration views; one seed the same; the world's streams are the
ones it always drew from; and a new random draw in the package must come from the streams or be listed below with
why it may not.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.seeds import MAX_INTEGER_SEED, RunSeeds, Stream

PKG = Path(__file__).resolve().parents[1] / "bt_grasp"


def test_the_worlds_streams_are_the_ones_it_always_drew_from() -> None:
    """``SeedSequence(seed).spawn(4)`` was the world's (objects, camera, faults) and the D435 recorder's (depth)."""
    for seed in (0, 5, 2**40 + 3):
        children = np.random.SeedSequence(seed).spawn(4)
        for stream in (Stream.OBJECTS, Stream.CAMERA, Stream.FAULTS, Stream.DEPTH_IMAGER):
            old = np.random.default_rng(children[int(stream)]).random(8)
            assert np.array_equal(RunSeeds(seed).generator(stream).random(8), old)


def test_streams_differ_from_each_other_and_between_seeds_and_repeat_for_one_seed() -> None:
    values = {(seed, stream): RunSeeds(seed).integer(stream) for seed in range(20) for stream in Stream}
    assert len(set(values.values())) == len(values)  # no two (seed, stream) pairs share an integer seed
    assert all(1 <= v <= MAX_INTEGER_SEED for v in values.values())
    assert RunSeeds(7).integer(Stream.GRASPS) == RunSeeds(7).integer(Stream.GRASPS)
    assert np.array_equal(RunSeeds(7).generator(Stream.IK).random(4), RunSeeds(7).generator(Stream.IK).random(4))


def _bottle() -> object:
    from bt_grasp.perception.results import Detection

    xy, size = (0.48, 0.0), (0.058, 0.058, 0.187)
    corners = tuple((xy[0] + a * size[0] / 2, xy[1] + b * size[1] / 2) for a, b in ((1, 1), (-1, 1), (-1, -1), (1, -1)))
    return Detection("green", (0, 0, 1, 1), (xy[0], xy[1], size[2] / 2), size, 0.0, 500, 1.0,
                     footprint_base_m=corners, shape="round")


def _sampled(seed: int) -> list[tuple[float, ...]]:
    """The grasps PlanGrasp would sample on a bottle with the run's grasp stream of ``seed``."""
    from bt_grasp.perception.antipodal import rank_grasps
    from bt_grasp.perception.results import Detection

    bottle = _bottle()
    assert isinstance(bottle, Detection)
    ranked = rank_grasps(bottle, seed=RunSeeds(seed).integer(Stream.GRASPS))
    assert ranked.ok
    return [tuple(np.round(c.T_base_tcp_grasp[:3, 3], 6)) for c in ranked.candidates if "antipodal" in c.reason]


def test_two_seeds_give_different_grasp_samples_and_one_seed_the_same() -> None:
    first, again, other = _sampled(3), _sampled(3), _sampled(4)
    assert first and first == again
    assert first != other


def test_a_runs_cell_draws_its_planner_ik_and_calibration_from_the_streams() -> None:
    from bt_grasp.behaviours.cell import make_cell
    from bt_grasp.motion.kinematics import SeededKinematics
    from bt_grasp.scene.format import load_scene

    scene = load_scene(PKG.parent / "scenes" / "tabletop.yaml")
    cells = {seed: make_cell(object(), object(), object(), scene, seed) for seed in (0, 1)}  # type: ignore[arg-type]
    for seed, cell in cells.items():
        assert cell.planner_options.seed == RunSeeds(seed).integer(Stream.PLANNER)
        assert isinstance(cell.kinematics, SeededKinematics)
        assert cell.kinematics.seed == RunSeeds(seed).integer(Stream.IK)
        assert np.array_equal(cell.seeds.generator(Stream.CALIBRATION).random(3),
                              RunSeeds(seed).generator(Stream.CALIBRATION).random(3))
    assert cells[0].planner_options.seed != cells[1].planner_options.seed


def test_ik_restarts_follow_the_runs_stream() -> None:
    """IK's random restarts (after ``q_current``) draw from the run's IK stream when the caller gives none."""
    from bt_grasp.motion.kinematics import ArmKinematics, IKOptions, SeededKinematics

    arm = ArmKinematics()
    q_far = np.array([0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0])
    target = arm.fk(np.array([0.9, -1.2, 1.4, -1.6, -1.5, 0.3]))
    options = IKOptions(max_iterations=15)  # short restarts: which of the arm's branches each finds is the draw's

    def found(seed: int) -> tuple[tuple[float, ...], ...]:
        solutions, _ = SeededKinematics(arm, RunSeeds(seed).integer(Stream.IK)).ik_solutions(
            target, q_far, seeds=8, options=options)
        return tuple(tuple(np.round(q, 6)) for q in solutions)

    assert found(0) == found(0)
    assert len({found(seed) for seed in range(4)}) > 1


#: every place in the package that makes a random generator not from ``bt_grasp.seeds``, and why it may
ALLOWED_GENERATORS: dict[str, str] = {
    "bt_grasp/seeds.py": "the streams themselves",
    "bt_grasp/faults/injector.py": "one child per fault of the run's FAULTS stream (spawn keys under it)",
    "bt_grasp/motion/kinematics.py": "the model's default for a caller with no run (tests, tools); a run's cell "
                                     "wraps it in SeededKinematics on the IK stream",
    "bt_grasp/motion/planner.py": "from PlannerOptions.seed, which a run sets from its PLANNER stream",
    "bt_grasp/motion/analytic_ik.py": "32 fixed self-checks of the closed-form IK, the same every time",
    "bt_grasp/perception/antipodal.py": "from the seed a caller passes (a run: its GRASPS stream); 0 with none",
    "bt_grasp/perception/segment.py": "from the seed a caller passes (a run: its PERCEPTION stream)",
    "bt_grasp/perception/calibration.py": "the untilted central view: its draws have zero width (deterministic)",
    "bt_grasp/sim/camera.py": "the noise sweep benchmark's variants, from the benchmark's own seed",
    "bt_grasp/sim/labelling.py": "the detector's dataset tool, from the dataset's seed",
    "bt_grasp/tree/stand_in.py": "a dry run's --random outcomes, from its --random-seed (no world, no run seed)",
}
_GENERATOR = re.compile(r"default_rng\(|SeedSequence\(|random\.Random\(|RandomState\(|np\.random\.seed\(")


def test_every_random_generator_comes_from_the_seed_path_or_says_why_not() -> None:
    found = sorted({str(p.relative_to(PKG.parent)) for p in PKG.rglob("*.py")
                    if _GENERATOR.search(p.read_text()) and "bt_grasp/bench/" not in str(p)})
    assert [f for f in found if f not in ALLOWED_GENERATORS] == []
    assert [f for f in ALLOWED_GENERATORS if f not in found] == []  # the list stays honest


@pytest.mark.parametrize("stream", list(Stream))
def test_every_stream_is_in_the_docs_table(stream: Stream) -> None:
    import bt_grasp.seeds

    assert f"``{stream.name}``" in (bt_grasp.seeds.__doc__ or "")
