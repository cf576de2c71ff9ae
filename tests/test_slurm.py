"""The SLURM launcher's logic without SLURM: which runs are submitted and how they are grouped,
what the partition allows, one-line errors, the ledger and the wait loop (on fake jobs and a
fake queue). `make slurm-check` runs the real thing on a single-node SLURM."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import pytest
from hydra.core.utils import JobReturn, JobStatus
from omegaconf import OmegaConf

from mediated_transfer.config.compose import ConfigError
from mediated_transfer.provenance import judge
from mediated_transfer.slurm import cluster, errors, jobs, watch
from mediated_transfer.slurm.cluster import ClusterError, Partition
from mediated_transfer.slurm.ledger import Ledger


# --- which runs are submitted, and in which jobs -------------------------------------------

def _cfg(sweep_dir: Path, cell: str, seed: int, rerun_stale: bool = False):
    return OmegaConf.create({"cell": cell, "seed": seed, "rerun_stale": rerun_stale,
                             "hydra": {"sweep": {"dir": str(sweep_dir), "subdir": "${cell}/seed=${seed}"}}})


def _finish(folder: Path) -> None:
    folder.mkdir(parents=True)
    (folder / "result.json").write_text("{}")


def test_plan_composes_once_per_cell_and_sets_each_seed(tmp_path):
    loaded = []

    def load(overrides):
        loaded.append(overrides)
        cell = overrides[0].split("=")[1]
        return _cfg(tmp_path, cell, 0)

    overrides = [[f"cell={c}", f"seed={s}"] for c in ("a", "b") for s in range(3)]
    runs = jobs.plan_runs(overrides, 10, load)
    assert len(loaded) == 2  # seeds do not change the rest of a config
    assert [r.folder.relative_to(tmp_path).as_posix() for r in runs] == \
        [f"{c}/seed={s}" for c in ("a", "b") for s in range(3)]
    assert [r.index for r in runs] == list(range(10, 16))


def test_finished_runs_are_not_submitted_but_stale_ones_are_when_recomputed(tmp_path, monkeypatch):
    stale = {"b_1/seed=0"}
    monkeypatch.setattr(judge.RunResult, "read", staticmethod(lambda folder: SimpleNamespace(
        stale=lambda: "other code" if Path(folder).relative_to(tmp_path).as_posix() in stale else None,
        **_run_of(Path(folder)))))
    monkeypatch.setattr(judge, "stale", lambda result: result.stale())  # the judge's word on a fake run
    _finish(tmp_path / "a_1/seed=0")
    _finish(tmp_path / "b_1/seed=0")
    _finish(tmp_path / "b_1/seed=1")
    (tmp_path / "b_1/seed=1/result.json").write_text('{"moved": "from a_1/seed=0"}')  # another cell's run
    for rerun_stale, submitted in ((False, ["a_1/seed=1", "b_1/seed=1"]),
                                   (True, ["a_1/seed=1", "b_1/seed=0", "b_1/seed=1"])):
        runs = [jobs.PlannedRun((), i, _cfg(tmp_path, c, s, rerun_stale), tmp_path / f"{c}/seed={s}")
                for i, (c, s) in enumerate([("a_1", 0), ("a_1", 1), ("b_1", 0), ("b_1", 1)])]
        finished, pending = jobs.split_finished(runs)
        assert [r.folder.relative_to(tmp_path).as_posix() for r in pending] == submitted
        assert len(finished) + len(pending) == 4


def _run_of(folder: Path) -> dict:
    """The cell and seed of the run a fake result.json holds: its folder's, unless it says it was moved."""
    moved = json.loads((folder / "result.json").read_text()).get("moved")
    cell, seed = (moved or f"{folder.parent.name}/{folder.name}").split("/")
    strategy, n_source = cell.rsplit("_", 1)
    return {"strategy": strategy, "n_source": int(n_source), "seed": int(seed.removeprefix("seed="))}


def test_is_finished_agrees_with_run_job_skipping(tmp_path, monkeypatch):
    # app.run_job skips a found result unless it is stale and rerun_stale is set.
    assert not jobs.is_finished(tmp_path / "missing", rerun_stale=False)
    _finish(tmp_path / "x")
    for stale in (None, "other code"):
        monkeypatch.setattr(judge.RunResult, "read", staticmethod(lambda folder: SimpleNamespace(stale=lambda: stale)))
        monkeypatch.setattr(judge, "stale", lambda result: result.stale())
        for rerun_stale in (False, True):
            assert jobs.is_finished(tmp_path / "x", rerun_stale) == (not (stale and rerun_stale))


def test_runs_are_grouped_in_sweep_order():
    runs = list(range(7))
    assert jobs.group_runs(runs, 3) == [[0, 1, 2], [3, 4, 5], [6]]
    assert jobs.group_runs(runs, 1) == [[r] for r in runs]
    assert jobs.group_runs(runs, 100) == [runs]
    assert jobs.group_runs([], 4) == []
    for bad in (0, -1, 2.5, "2", True):
        with pytest.raises(ConfigError, match=r"hydra.launcher.runs_per_job=.*must be an integer >= 1"):
            jobs.group_runs(runs, bad)


# --- what the partition allows ----------------------------------------------------------------

@pytest.mark.parametrize("text, minutes", [
    ("infinite", float("inf")), ("UNLIMITED", float("inf")), ("30", 30), ("30:00", 30),
    ("1:00:00", 60), ("2-00:00:00", 2880), ("1-12", 2160), ("0:30:30", 30.5)])
def test_time_limits_are_read_in_minutes(text, minutes):
    assert cluster.parse_time_limit(text) == minutes


SINFO = "debug*|1:00:00|23081|2\nlong|7-00:00:00|64000+|32\nlong|7-00:00:00|32000|16\n"


def test_sinfo_gives_each_partition_with_its_most_restrictive_nodes():
    parts = {p.name: p for p in cluster.parse_sinfo(SINFO)}
    assert parts["debug"] == Partition("debug", True, 60, 23081, 2)
    assert parts["long"] == Partition("long", False, 7 * 1440, 32000, 16)


@pytest.mark.parametrize("partition, timeout, mem, cpus, message", [
    ("nosuch", 30, 1, 1, r"^hydra.launcher.partition=nosuch: no such partition; allowed: debug, long$"),
    (None, 61, 1, 1, r"^hydra.launcher.timeout_min=61 is above partition debug's time limit of 60 min"),
    ("debug", 30, 23, 1, r"^hydra.launcher.mem_gb=23 is above the memory of partition debug's nodes \(22.5 GB\)"),
    ("debug", 30, 1, 4, r"^hydra.launcher.cpus_per_task=4 is above the CPUs of partition debug's nodes \(2\)"),
])
def test_a_request_slurm_would_refuse_or_never_start_is_one_line(partition, timeout, mem, cpus, message):
    with pytest.raises(ClusterError, match=message) as caught:
        cluster.check_request(cluster.parse_sinfo(SINFO), partition, timeout, mem, cpus)
    assert "\n" not in str(caught.value)


def test_a_fitting_request_goes_to_the_named_or_default_partition():
    parts = cluster.parse_sinfo(SINFO)
    assert cluster.check_request(parts, None, 60, 22, 2).name == "debug"
    assert cluster.check_request(parts, "long", 10000, None, None).name == "long"


def test_missing_slurm_commands_are_one_line(monkeypatch):
    monkeypatch.setattr(cluster.shutil, "which", lambda name: None)
    with pytest.raises(ClusterError, match=r"^sinfo not found: hydra/launcher=slurm runs on a SLURM login node"):
        cluster.partitions()


def test_squeue_lines_give_state_and_reason_per_array_task():
    assert cluster.parse_squeue("12_0|RUNNING|None\n12_1|PENDING|Resources\n\n") == \
        {"12_0": ("RUNNING", "None"), "12_1": ("PENDING", "Resources")}


# --- one-line errors --------------------------------------------------------------------------

def test_sbatch_errors_keep_sbatchs_reason_and_name_the_key():
    text = ("Command '['sbatch', '/x/submission_file.sh']' returned non-zero exit status 1.\n"
            "sbatch: error: Memory specification can not be satisfied\n"
            "sbatch: error: Batch job submission failed: Requested node configuration is not available\n")
    line = errors.sbatch_error(text)
    assert line == ("sbatch refused the jobs: Batch job submission failed: Requested node configuration "
                    "is not available")
    assert errors.sbatch_error("sbatch: error: invalid partition specified: x").endswith(
        "check hydra.launcher.partition (sinfo lists them)")


def test_a_job_killed_at_its_time_limit_is_one_line_naming_timeout_min(tmp_path):
    log = tmp_path / "12_3_0_log.err"
    log.write_text("... progress ...\nslurmstepd: error: *** JOB 15 ON vm CANCELLED AT 2026-12-01T19:00 "
                   "DUE TO TIME LIMIT ***\n")
    line = errors.ended_without_result("12_3", ["a/seed=0", "a/seed=1"], log, 30, 2)
    assert line.startswith("job 12_3 (a/seed=0, a/seed=1) hit its time limit "
                           "(hydra.launcher.timeout_min=30 for 2 runs)")
    assert line.endswith(f"log: {log}") and "\n" not in line
    log.write_text("slurmstepd: error: Detected 1 oom_kill event in StepId=15.batch\n")
    assert "ran out of memory: raise hydra.launcher.mem_gb" in errors.ended_without_result("1", ["r"], log, 30, 1)


def test_a_run_stopped_by_submitits_time_limit_signal_is_one_line_naming_timeout_min():
    from submitit.core.utils import UncompletedJobError

    ret = JobReturn()
    ret.status, ret._return_value = JobStatus.FAILED, UncompletedJobError(
        "Job not requeued because: timed-out too many times.")
    assert errors.reached_time_limit(ret)
    line = errors.run_failed("a/seed=1", ret, Path("x.err"), 30, 4)
    assert line.startswith("run a/seed=1 stopped: its job reached its time limit "
                           "(hydra.launcher.timeout_min=30 for 4 runs;")
    ret._return_value = ValueError("other")
    assert not errors.reached_time_limit(ret)


# --- the ledger: a rerun waits for queued jobs instead of resubmitting -------------------------

def test_ledger_returns_only_runs_whose_job_is_still_queued(tmp_path):
    ledger = Ledger(tmp_path)
    ledger.record({"a/seed=0": {"job": "5_0", "folder": "f"}, "a/seed=1": {"job": "5_1", "folder": "f"}})
    ledger.record({"b/seed=0": {"job": "6_0", "folder": "f"}})
    queued = {"5_1": ("RUNNING", "None"), "6_0": ("PENDING", "Priority")}
    assert ledger.live(["a/seed=0", "a/seed=1", "b/seed=0", "c/seed=0"], queued) == {
        "a/seed=1": {"job": "5_1", "folder": "f"}, "b/seed=0": {"job": "6_0", "folder": "f"}}
    assert json.loads(ledger.path.read_text())["a/seed=0"]["job"] == "5_0"


# --- waiting: results, progress, failures --------------------------------------------------------

class FakeJob:
    def __init__(self, folder: Path, job_id: str, runs: list[str], fail: set[str] = frozenset()):
        self.job_id = job_id
        self.paths = SimpleNamespace(result_pickle=folder / f"{job_id}_result.pkl",
                                     stderr=folder / f"{job_id}_log.err")
        self.runs, self.fail = runs, fail

    def finish(self):
        self.paths.result_pickle.write_text("done")

    def results(self):
        out = []
        for run in self.runs:
            ret = JobReturn()
            ret.status = JobStatus.FAILED if run in self.fail else JobStatus.COMPLETED
            ret._return_value = ValueError(f"bad {run}\nsecond line") if run in self.fail else {"run": run}
            out.append((run, ret))
        return [out]


def _wait(tmp_path, subs, queue, **kw):
    clock = iter(range(0, 10_000, 5))
    return watch.wait(subs, tmp_path, "t/smoke", every_s=5, timeout_min=30, runs_per_job=2, queue=queue,
                      cancel=kw.get("cancel", lambda ids: None), sleep=kw.get("sleep", lambda s: None),
                      clock=lambda: next(clock))


def test_wait_collects_every_run_and_names_failed_ones_in_one_line(tmp_path):
    ok = FakeJob(tmp_path, "7_0", ["a/seed=0", "a/seed=1"])
    bad = FakeJob(tmp_path, "7_1", ["b/seed=0", "b/seed=1"], fail={"b/seed=1"})
    ticks = []

    def queue():
        ticks.append(1)
        if len(ticks) == 2:
            ok.finish(), bad.finish()
        return {"7_0": ("RUNNING", "None"), "7_1": ("PENDING", "Resources")}

    outcome = _wait(tmp_path, [watch.Submitted(ok, ok.runs), watch.Submitted(bad, bad.runs)], queue)
    assert [r.return_value["run"] for r in outcome.returns] == ["a/seed=0", "a/seed=1", "b/seed=0"]
    assert outcome.errors == [f"run b/seed=1 failed: ValueError: bad b/seed=1; log: {bad.paths.stderr}"]


def test_a_job_that_leaves_the_queue_without_result_fails_after_a_grace_period(tmp_path):
    job = FakeJob(tmp_path, "8_0", ["a/seed=0"])
    job.paths.stderr.write_text("*** JOB 8 ON vm CANCELLED AT now DUE TO TIME LIMIT ***\n")
    outcome = _wait(tmp_path, [watch.Submitted(job, job.runs)], lambda: {})
    assert len(outcome.errors) == 1 and "hit its time limit" in outcome.errors[0]


def test_a_job_that_can_never_start_cancels_the_sweep_in_one_line(tmp_path):
    job = FakeJob(tmp_path, "9_0", ["a/seed=0"])
    cancelled = []
    with pytest.raises(ClusterError, match=r"^job 9_0 can never start \(PartitionTimeLimit\): .*timeout_min"):
        _wait(tmp_path, [watch.Submitted(job, job.runs)], lambda: {"9_0": ("PENDING", "PartitionTimeLimit")},
              cancel=cancelled.append)
    assert cancelled == [["9_0"]]


def test_status_line_counts_the_sweep_and_the_queue(tmp_path):
    (tmp_path / "a/seed=0").mkdir(parents=True)
    (tmp_path / "a/seed=0/result.json").write_text("{}")
    from mediated_transfer.sweep import write_plan

    write_plan(tmp_path, ["a/seed=0", "a/seed=1", "b/seed=0"])
    line = watch.status_line(tmp_path, "t/smoke", "a/seed=1",
                             {"1_0": ("RUNNING", "None"), "1_1": ("PENDING", "Priority"), "1_2": ("PENDING", "None")})
    assert line.startswith("[t/smoke 1/3")
    assert line.endswith("] SLURM jobs: 1 running, 2 pending (Priority)")


# --- the preset and the launcher inside Hydra -----------------------------------------------------

def test_the_preset_composes_to_this_launcher_with_its_keys():
    from mediated_transfer.config.compose import compose_config

    launcher = compose_config(["hydra/launcher=slurm", "hydra.launcher.runs_per_job=5"], hydra=True).hydra.launcher
    assert launcher._target_ == "hydra_plugins.mediated_transfer_launcher.slurm_launcher.MediatedSlurmLauncher"
    assert (launcher.runs_per_job, launcher.wait, launcher.mem_gb) == (5, True, 1)


@pytest.mark.slow
def test_resubmitting_a_finished_sweep_submits_nothing(tmp_path, monkeypatch):
    from hydra_plugins.mediated_transfer_launcher import slurm_launcher

    from .test_sweep import _common, _run_cli
    from .test_tracking import fresh_store

    fresh_store(tmp_path)
    common = ["experiment=table2_rbf", "cell=none_0", *_common(tmp_path, tmp_path / "cache")]
    _run_cli(*common, "hydra/launcher=basic")
    monkeypatch.setattr(cluster, "partitions", lambda: cluster.parse_sinfo(SINFO))
    monkeypatch.setattr(cluster, "queue", lambda: {})

    submitted = []

    def submit(self, groups, name, errors, lockstep=False):
        submitted.extend(name[r.folder] for group in groups for r in group)
        return []

    monkeypatch.setattr(slurm_launcher.MediatedSlurmLauncher, "_submit", submit)
    _run_cli(*common, "hydra/launcher=slurm")
    assert submitted == []
    # ... while a run without result is
    (tmp_path / "multirun/table2_rbf/smoke/none_0/seed=0/result.json").unlink()
    _run_cli(*common, "hydra/launcher=slurm")
    assert submitted == ["none_0/seed=0"]


@pytest.mark.slow
def test_lockstep_submits_one_job_per_group_of_a_cells_unfinished_seeds(tmp_path, monkeypatch):
    from hydra_plugins.mediated_transfer_launcher import slurm_launcher

    from .test_sweep import _common, _run_cli
    from .test_tracking import fresh_store

    fresh_store(tmp_path)
    common = ["experiment=table2_rbf", "cell=none_0,regular_1", *_common(tmp_path, tmp_path / "cache"),
              "scale.seeds=3"]
    _run_cli(*common, "seed=1", "hydra/launcher=basic")  # none_0 and regular_1 seed 1 are finished
    monkeypatch.setattr(cluster, "partitions", lambda: cluster.parse_sinfo(SINFO))
    monkeypatch.setattr(cluster, "queue", lambda: {})
    submitted = []

    def submit(self, groups, name, errors, lockstep=False):
        submitted.append((lockstep, sorted(sorted(name[r.folder] for r in group) for group in groups)))
        return []

    monkeypatch.setattr(slurm_launcher.MediatedSlurmLauncher, "_submit", submit)
    _run_cli(*common, "hydra/launcher=slurm", "lockstep.runs=2")
    assert submitted == [(True, [["none_0/seed=0", "none_0/seed=2"], ["regular_1/seed=0", "regular_1/seed=2"]])]
    submitted.clear()
    _run_cli(*common, "hydra/launcher=slurm", "hydra.launcher.runs_per_job=2")  # no lockstep: packed
    assert submitted == [(False, [["none_0/seed=0", "regular_1/seed=0"], ["none_0/seed=2", "regular_1/seed=2"]])]
