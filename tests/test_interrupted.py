"""A stopped command's launcher ends the MLflow runs its dead workers left RUNNING
(sweep/interrupted.py): KILLED, or FINISHED and logged in full when the result was written; a
run another process still computes (its claim held) is left alone."""

from __future__ import annotations

import os
import time

from mediated_transfer.sweep import interrupted, tracking
from mediated_transfer.sweep.claim import claimed
from mediated_transfer.sweep.identity import run_where

from .test_tracking import fresh_store, synthetic_result


def test_runs_left_running_by_dead_workers_end_killed_or_finished_and_claimed_ones_are_left(tmp_path, monkeypatch):
    monkeypatch.setattr(interrupted, "CLAIM_WAIT_S", 0.3)
    settings = tracking.TrackingSettings(fresh_store(tmp_path), str(tmp_path / "artifacts"))
    names = ["computing", "written", "written_before", "claimed"]
    folders = {name: tmp_path / "multirun" / name / "seed=0" for name in names}
    folders["written_before"].mkdir(parents=True)
    synthetic_result().write(folders["written_before"])  # a stale result the run recomputed
    old = time.time() - 60
    os.utime(folders["written_before"] / "result.json", (old, old))
    live = {}
    for name, folder in folders.items():
        where = run_where(tmp_path, folder)
        live[name] = tracking.LiveRun(settings, "table_x", key=f"{where}@abc.def", run_name=name,
                                      params={"seed": "0"}, tags={"table": "table_x", "cell": name})
        live[name].evaluation(100, 2.0, 0.1)
    synthetic_result().write(folders["written"])  # its worker was killed while logging it
    planned = [interrupted.PlannedRun(f, run_where(tmp_path, f), "table_x", settings) for f in folders.values()]

    with claimed(folders["claimed"]) as mine:  # another launch computes it
        assert mine
        assert interrupted.settle(planned) == 3

    runs = {r.info.run_name: r for r in tracking.find_runs(settings, "table_x")}
    assert {name: r.info.status for name, r in runs.items()} == {
        "computing": "KILLED", "written": "FINISHED", "written_before": "KILLED", "claimed": "RUNNING"}
    assert runs["written"].data.metrics["reward_loss"] == synthetic_result().reward_loss
    assert {a.path for a in settings.client().list_artifacts(runs["written"].info.run_id)} == {"result.json", "curve.csv"}
    assert interrupted.settle(planned) == 1  # its claim free (its holder gone): the last one ends
    assert interrupted.settle(planned) == 0  # and nothing twice


def test_a_stopped_command_says_what_stopped_it_and_what_is_left_in_one_line(tmp_path):
    folders = [tmp_path / f"seed={k}" for k in range(3)]
    synthetic_result().write(folders[0])
    runs = [interrupted.PlannedRun(f, f.name, "table_x", None) for f in folders]
    assert interrupted.exit_line(runs, KeyboardInterrupt()) == (
        "interrupted (SIGINT): 1 of 3 runs finished, 2 left; run the same command to resume (finished runs are kept)", 130)
    assert interrupted.exit_line(runs, interrupted.Interrupted(15))[1] == 143
    lost = interrupted.worker_lost_line(RuntimeError(
        "A worker process managed by the executor was unexpectedly terminated. ...\n\n"
        "The exit codes of the workers are {SIGKILL(-9)}"))
    assert lost == "a worker process died ({SIGKILL(-9)})"
    assert interrupted.exit_line(runs, interrupted.WorkerLost(lost))[0].startswith(f"{lost}: 1 of 3 runs finished")
