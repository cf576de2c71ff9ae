"""The one judge of a stored run (provenance/judge.py): each of its four verdicts and its line,
as the sweep, the launchers and the reports receive them. What each caller then does with a
verdict is tested with the caller (test_sweep, test_stored, test_faults_folders, test_slurm,
test_reports)."""

from __future__ import annotations

import pytest

from mediated_transfer.provenance import judge as judge_module
from mediated_transfer.provenance.judge import RECOMPUTE, REUSE, SET_ASIDE, STALE, judge
from mediated_transfer.results import RESULT_FILE

from .test_tracking import synthetic_result

PLACE = ("regular_15", 0)


def test_an_empty_folder_is_computed(tmp_path):
    verdict = judge(tmp_path / "regular_15" / "seed=0", place=PLACE)
    assert (verdict.action, verdict.reason, verdict.found, verdict.kept) == (RECOMPUTE, None, False, False)


def test_a_whole_current_run_is_reused(tmp_path):
    folder = tmp_path / "regular_15" / "seed=0"
    synthetic_result().write(folder)
    verdict = judge(folder, place=PLACE)
    assert (verdict.action, verdict.reason, verdict.found, verdict.kept) == (REUSE, None, True, True)
    assert verdict.result is not None and verdict.result.seed == 0


def test_a_run_of_other_code_is_reported_stale_or_recomputed_on_request(tmp_path):
    folder = tmp_path / "regular_15" / "seed=0"
    result = synthetic_result()
    result.code = {**result.code, "commit": "0" * 40, "dirty": False, "digest": "0" * 16}  # as if other code wrote it
    result.write(folder)
    kept = judge(folder, place=PLACE)
    assert (kept.action, kept.kept) == (STALE, True)
    assert kept.reason.startswith("computed by other code: commit 0000000000, code digest 0000000000000000; now ")
    again = judge(folder, place=PLACE, rerun_stale=True)
    assert (again.action, again.reason, again.kept) == (RECOMPUTE, kept.reason, False)


def test_a_damaged_run_or_another_cells_run_is_set_aside_with_its_line(tmp_path):
    moved = tmp_path / "none_0" / "seed=0"
    synthetic_result().write(moved)  # regular_15's run in none_0's folder
    verdict = judge(moved, place=("none_0", 0))
    assert (verdict.action, verdict.found, verdict.kept, verdict.result) == (SET_ASIDE, True, False, None)
    assert verdict.reason == (f"{moved / RESULT_FILE}: holds the run regular_15 seed=0, not this folder's "
                              "none_0 seed=0: moved or copied here")

    damaged = tmp_path / "regular_15" / "seed=0"
    damaged.mkdir(parents=True)
    (damaged / RESULT_FILE).write_text('{"algorithm": ')
    verdict = judge(damaged, place=PLACE)
    assert verdict.action == SET_ASIDE and verdict.reason.startswith(f"{damaged / RESULT_FILE}: is not valid JSON")


def test_only_the_verdicts_that_need_it_digest_the_code(tmp_path, monkeypatch):
    # A report, or a launcher that keeps stale runs, asks only whether a run is there and whole:
    # digesting its code (imports and a walk of its closure) would cost them seconds per run kind.
    folder = tmp_path / "regular_15" / "seed=0"
    synthetic_result().write(folder)

    def digested(result):
        raise AssertionError("digested")

    monkeypatch.setattr(judge_module, "stale", digested)
    verdict = judge(folder, place=PLACE)
    assert verdict.kept and verdict.found and verdict.damaged is None
    with pytest.raises(AssertionError, match="digested"):
        judge(folder, place=PLACE, rerun_stale=True).kept
