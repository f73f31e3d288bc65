# SPDX-License-Identifier: BSD-3-Clause
"""The metrics of bench/datasets/localize_benchmark.py on hand-made error series: position error
scan by scan, time lost, runs ending lost, recovery after a kidnap, the per-condition summary,
and the time subset of a CARMEN log."""

import importlib.util
import math
import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "bench", "datasets"))  # as when the script runs: its `common` beside it
spec = importlib.util.spec_from_file_location("localize_benchmark", os.path.join(ROOT, "bench", "datasets", "localize_benchmark.py"))
bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench)


def test_position_error_is_the_distance_at_the_same_scan_and_refuses_other_scans():
    reference = [(0.0, 0.0, 0.0, 0.0), (1.0, 1.0, 0.0, 0.0), (2.0, 2.0, 0.0, 0.0)]
    trajectory = [(0.0, 3.0, 4.0, 1.0), (1.0, 1.0, 0.5, 0.0)]  # a prefix: a time subset of the log
    assert bench.position_errors(trajectory, reference) == pytest.approx([5.0, 0.5])
    with pytest.raises(ValueError, match="not the same scans"):
        bench.position_errors([(0.5, 0.0, 0.0, 0.0)], reference)
    with pytest.raises(ValueError, match="4 scans"):
        bench.position_errors(reference + [(3.0, 0.0, 0.0, 0.0)], reference)


def test_time_lost_counts_errors_above_the_threshold():
    assert bench.lost_fraction([0.1, 2.0, 0.5, 1.5], 1.0) == 0.5
    assert bench.lost_fraction([1.0, 0.2], 1.0) == 0.0  # at the threshold is not lost
    assert math.isnan(bench.lost_fraction([], 1.0))


def test_a_run_ends_lost_when_its_whole_last_stretch_is_above_the_threshold():
    stamps = [float(t) for t in range(30)]
    assert bench.ends_lost(stamps, [0.1] * 15 + [3.0] * 15, 1.0, tail_s=10.0)
    assert not bench.ends_lost(stamps, [0.1] * 15 + [3.0] * 14 + [0.2], 1.0, tail_s=10.0)
    assert not bench.ends_lost(stamps, [3.0] * 15 + [0.1] * 15, 1.0, tail_s=10.0)


def test_recovery_is_the_time_until_the_error_is_back_below_the_threshold_and_stays():
    stamps = [float(t) for t in range(100)]
    # Kidnapped at 20 s: 5 m off; a brief dip below at 30-32 s (does not stay); back for good at 41 s.
    errors = [0.1] * 20 + [5.0] * 10 + [0.5] * 3 + [4.0] * 8 + [0.2] * 59
    assert bench.recovery_time(stamps, errors, 20.0, 1.0, 10.0) == pytest.approx(21.0)
    # Without a hold the dip counts.
    assert bench.recovery_time(stamps, errors, 20.0, 1.0, 0.0) == pytest.approx(10.0)
    # Never back: None; the error never left: 0.
    assert bench.recovery_time(stamps, [0.1] * 20 + [5.0] * 80, 20.0, 1.0, 10.0) is None
    assert bench.recovery_time(stamps, [0.1] * 100, 20.0, 1.0, 10.0) == 0.0
    # Back below near the end of the run: counts, the run ended before the hold did.
    assert bench.recovery_time(stamps, [0.1] * 20 + [5.0] * 75 + [0.1] * 5, 20.0, 1.0, 10.0) == pytest.approx(75.0)
    # Errors before the kidnap do not count.
    assert bench.recovery_time(stamps, [5.0] * 20 + [0.1] * 80, 20.0, 1.0, 10.0) == 0.0


def test_the_summary_of_a_condition():
    def run(mean, median, lost, ends, recovery, kidnapped=True):
        return {"mean_error_m": mean, "median_error_m": median, "lost_fraction": lost, "ends_lost": ends,
                "kidnapped": kidnapped, "recovery_s": recovery, "us_per_scan": 100.0}
    summary = bench.summarize_runs([run(0.1, 0.05, 0.0, False, 12.0), run(0.3, 0.07, 0.2, False, 30.0),
                                    run(2.0, 1.5, 0.6, True, None)])
    assert summary["runs"] == 3
    assert summary["mean_error_m"] == pytest.approx(0.8)
    assert summary["median_error_m"] == pytest.approx(0.07)
    assert summary["lost_fraction"] == pytest.approx(0.8 / 3)
    assert summary["failed_runs"] == 1
    assert (summary["kidnaps"], summary["recovered"]) == (3, 2)
    assert summary["recovery_median_s"] == pytest.approx(21.0)


def test_the_time_subset_keeps_the_lines_up_to_the_duration_in_file_order(tmp_path):
    log = tmp_path / "log.clf"
    lines = ["# comment\n", "ODOM 0 0 0 0 0 0 100.0 nohost 100.0\n"]
    for k, stamp in enumerate([100.0, 100.5, 100.4, 101.0, 102.5, 101.2]):  # a stamp steps back, as Intel's do
        lines.append(f"FLASER 2 1.0 1.0 {k} 0 0 {k} 0 0 {stamp} nohost {stamp}\n")
    log.write_text("".join(lines))
    out = tmp_path / "subset.clf"
    bench.time_subset(str(log), str(out), 2.0)
    kept = out.read_text().splitlines()
    assert kept[:2] == ["# comment", "ODOM 0 0 0 0 0 0 100.0 nohost 100.0"]
    assert [line.split()[-3] for line in kept[2:]] == ["100.0", "100.5", "100.4", "101.0"]  # stops at 102.5
