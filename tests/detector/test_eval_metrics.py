"""`detector eval`'s metric math against cases worked out by hand (never by calling the code for the answer).

Overlaps use the closed form of the probabilistic IoU of two equal boxes shifted by d along their width w:
B = 1.5 d²/w², IoU = 1 - sqrt(1 - exp(-B)); a box against itself gives 1 - sqrt(eps) (eps 1e-7), above 0.95.
Average precision integrates the precision envelope by the trapezoidal rule over recall 0, 0.01, ..., 1 with the
envelope's sentinel 0 at recall 1 (so a perfect class scores 1 - 0.01/2 = 0.995, as Ultralytics reports).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_grasp.detector.evaluate import Boxes, axis_error_deg, evaluate

NAMES = ("bar", "block", "disc")
BAR = [100.0, 100.0, 60.0, 20.0, 0.3]  # elongated: 60 x 20
BLOCK = [250.0, 120.0, 30.0, 30.0, 0.0]  # square: no direction
SHIFT = 14.0  # along the bar's width (its 60 px side): B = 1.5 (14/60)² = 0.081667, IoU = 0.71996


def _shifted(box: list[float], d: float) -> list[float]:
    cx, cy, w, h, r = box
    return [cx + d * math.cos(r), cy + d * math.sin(r), w, h, r]


def test_the_closed_form_overlap_used_below() -> None:
    b = 1.5 * (SHIFT / 60.0) ** 2
    assert 1 - math.sqrt(1 - math.exp(-b)) == pytest.approx(0.71996, abs=1e-5)


def test_a_perfect_detector_scores_0_995_and_half_the_labels_0_495() -> None:
    truth = [Boxes.of([BAR, BLOCK], [0, 1])]
    perfect = evaluate(truth, [Boxes.of([BAR, BLOCK], [0, 1], [0.9, 0.8])], NAMES)
    assert perfect.map50 == pytest.approx(0.995) and perfect.map50_95 == pytest.approx(0.995)
    assert [c.labels for c in perfect.per_class] == [1, 1, 0]
    # two bars, one found: the envelope is 1 up to recall 0.5 (51 points) then 0: 0.49 + 0.01 x 1/2 = 0.495
    two_bars = [Boxes.of([BAR, _shifted(BAR, 200)], [0, 0])]
    half = evaluate(two_bars, [Boxes.of([BAR], [0], [0.9])], NAMES)
    assert half.map50 == pytest.approx(0.495)
    # the disc has no label: it is not averaged in even when something predicts it
    stray = evaluate(truth, [Boxes.of([BAR, BLOCK, [400, 400, 10, 10, 0]], [0, 1, 2], [0.9, 0.8, 0.7])], NAMES)
    assert stray.map50 == pytest.approx(0.995)


def test_a_false_positive_ranked_first_halves_the_precision() -> None:
    # one bar label; a wrong box scores 0.9, the right one 0.8: precision 0 then 1/2 at recall 1; the envelope is
    # 1/2 from recall 0 to 0.99 and 0 at 1: 0.99 x 0.5 + 0.01 x 0.25 = 0.4975
    truth = [Boxes.of([BAR], [0])]
    found = evaluate(truth, [Boxes.of([_shifted(BAR, 300), BAR], [0, 0], [0.9, 0.8])], NAMES)
    assert found.per_class[0].ap50 == pytest.approx(0.4975)
    # the right box of the wrong class is a false positive of that class, never a true one
    wrong_class = evaluate(truth, [Boxes.of([BAR], [1], [0.9])], NAMES)
    assert wrong_class.map50 == 0.0
    # a "block" on the bar, ranked above the right block: a false positive of the block class (0.4975 again), not
    # a match of the bar's label
    both = [Boxes.of([BAR, BLOCK], [0, 1])]
    mixed = evaluate(both, [Boxes.of([BAR, BLOCK], [1, 1], [0.9, 0.8])], NAMES)
    assert mixed.per_class[1].ap50 == pytest.approx(0.4975) and mixed.per_class[0].ap50 == 0.0


def test_map50_95_counts_the_thresholds_a_match_passes() -> None:
    # IoU 0.71996 passes 0.50, 0.55, 0.60, 0.65, 0.70 and fails 0.75 ... 0.95: AP50-95 = 0.995 x 5 / 10
    truth = [Boxes.of([BAR], [0])]
    report = evaluate(truth, [Boxes.of([_shifted(BAR, SHIFT)], [0], [0.9])], NAMES)
    assert report.map50 == pytest.approx(0.995)
    assert report.map50_95 == pytest.approx(0.995 * 0.5)


def test_a_label_is_claimed_once_by_the_best_scoring_prediction() -> None:
    # two predictions on one label: the higher score takes it, the other is a false positive ranked second:
    # precision 1 at recall 1, then 1/2: the envelope is 1 everywhere up to the sentinel: 0.995
    truth = [Boxes.of([BAR], [0])]
    report = evaluate(truth, [Boxes.of([_shifted(BAR, 2.0), BAR], [0, 0], [0.6, 0.9])], NAMES)
    assert report.map50 == pytest.approx(0.995)


def test_angle_error_of_elongated_objects_only() -> None:
    assert axis_error_deg(np.array([0.0]), np.array([math.radians(179)]))[0] == pytest.approx(1.0)
    assert axis_error_deg(np.array([0.1]), np.array([0.1 + math.pi / 2]))[0] == pytest.approx(90.0)
    four = math.radians(4.0)
    seven = math.radians(7.0)
    truths = [Boxes.of([BAR, BLOCK], [0, 1]), Boxes.of([BAR], [0])]
    preds = [
        # the bar seen 4 degrees off; the block 20 degrees off (a square: no direction, not counted)
        Boxes.of([[*BAR[:4], BAR[4] + four], [*BLOCK[:4], math.radians(20)]], [0, 1], [0.9, 0.9]),
        # the same bar written the other way round (w and h swapped, angle + 90 degrees), 7 degrees off
        Boxes.of([[BAR[0], BAR[1], BAR[3], BAR[2], BAR[4] + math.pi / 2 - seven]], [0], [0.8]),
    ]
    report = evaluate(truths, preds, NAMES)
    assert report.angle_errors == 2
    assert report.median_angle_error_deg == pytest.approx(5.5)
    assert report.per_class[0].elongated == 2 and report.per_class[1].elongated == 0
    assert report.per_class[1].median_angle_error_deg is None
    # a prediction at or below the pipeline's threshold (0.25) gives no angle
    faint = evaluate([Boxes.of([BAR], [0])], [Boxes.of([BAR], [0], [0.25])], NAMES)
    assert faint.angle_errors == 0 and faint.median_angle_error_deg is None


def test_confusion_matrix_rows_true_columns_predicted() -> None:
    truths = [Boxes.of([BAR, BLOCK, [400.0, 300.0, 40.0, 40.0, 0.0]], [0, 1, 2])]
    preds = [Boxes.of(
        [BAR,  # a bar seen as a bar
         BLOCK,  # the block seen as a disc
         [50.0, 400.0, 30.0, 10.0, 0.0],  # a bar where nothing is: background -> bar
         [400.0, 300.0, 40.0, 40.0, 0.0]],  # the disc, too faint to count (0.2): the disc is missed
        [0, 2, 0, 2], [0.9, 0.8, 0.7, 0.2])]
    report = evaluate(truths, preds, NAMES)
    assert report.confusion == (
        (1, 0, 0, 0),  # bar: found as bar
        (0, 0, 1, 0),  # block: predicted disc
        (0, 0, 0, 1),  # disc: missed (background)
        (1, 0, 0, 0),  # background: one bar predicted where nothing was
    )
    assert [c.predictions for c in report.per_class] == [2, 0, 1]


def test_the_table_counts_the_predictions_its_ap_scores() -> None:
    """Issue 43, finding 11: two bar labels, one found at 0.9 and one at 0.1 (under the pipeline's 0.25): AP50 is
    0.995 because AP scores every prediction from 0.01 up (as Ultralytics does), so the table's prediction count is
    that one (2), with the pipeline's own count (1) beside it, and the table says which is which."""
    from bt_grasp.detector.evaluate import format_report

    two_bars = [Boxes.of([BAR, _shifted(BAR, 200)], [0, 0])]
    report = evaluate(two_bars, [Boxes.of([BAR, _shifted(BAR, 200)], [0, 0], [0.9, 0.1])], NAMES)
    assert report.per_class[0].ap50 == pytest.approx(0.995)
    bar = report.per_class[0]
    assert (bar.labels, bar.scored, bar.predictions) == (2, 2, 1)
    text = format_report(report)
    row = next(line for line in text.splitlines() if line.startswith("bar "))
    assert row.split()[:4] == ["bar", "2", "2", "1"], text
    assert "score >= 0.01" in text and "> 0.25" in text, text  # the table says which predictions each count holds
    assert max(len(line) for line in text.splitlines()) <= 80, text
