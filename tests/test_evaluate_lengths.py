"""scripts/evaluate_lengths.py's bookkeeping: which kind a line is, and the medians its table quotes."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

_spec = importlib.util.spec_from_file_location("evaluate_lengths", Path(__file__).parents[1] / "scripts" / "evaluate_lengths.py")
evaluate_lengths = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(evaluate_lengths)


@pytest.mark.parametrize("name, category, kind", [
    ("left_cuff", "long-sleeve-top", "sleeve cuff"), ("right_cuff", "short-sleeve-dress", "dress cuff"),
    ("hem", "sleeveless-top", "top hem"), ("hem", "short-skirt", "skirt or dress hem"),
    ("hem", "long-sleeve-dress", "skirt or dress hem"), ("left_hem", "long-pants", "long trousers' leg"),
    ("right_hem", "short-pants", "shorts' leg")])
def test_each_line_has_its_kind(name, category, kind):
    assert evaluate_lengths.line_kind(name, category) == kind


def test_the_summary_takes_medians_of_the_errors_and_of_their_sizes():
    def line(kind, error):
        return {"kind": kind, **{estimate: error for estimate in evaluate_lengths.ESTIMATES}}

    rows = [{"lines": {"left_cuff": line("sleeve cuff", e), "hem": line("top hem", -2 * e)},
             "body_cm": {"height": e, "leg": -e, "arm": 0.0}, "true_height_m": 1.6 + e / 100}
            for e in (-3.0, 1.0, 5.0)]
    summary = evaluate_lengths.summarise(rows)
    cuff = summary["lines"]["sleeve cuff"]
    assert cuff["lines"] == 3 and cuff["regressor"] == {"median_abs_cm": 3.0, "median_cm": 1.0}
    assert summary["lines"]["top hem"]["read_true_body"] == {"median_abs_cm": 6.0, "median_cm": -2.0}
    assert summary["body"]["height"]["median_cm"] == 1.0 and summary["body"]["leg"]["median_cm"] == -1.0
    assert summary["true_height_p10_p50_p90_m"][1] == pytest.approx(1.61)
    table = evaluate_lengths.table({"summary": summary})
    assert table[2].startswith("| sleeve cuff (3) | 3.0 (+1.0) |") and table[3].startswith("| top hem (3) | 6.0 (-2.0) |")
