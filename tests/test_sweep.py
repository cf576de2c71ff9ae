"""End to end at smoke scale, in temporary folders: every experiment sweeps, reports and tracks;
an interrupted sweep completes on re-running without recomputing or duplicating a run; a
single run is skipped when its result exists; the submitit local launcher runs jobs."""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hydra.core.global_hydra import GlobalHydra

from mediated_transfer.sweep import tracking
from mediated_transfer.app import cli, run_job
from mediated_transfer.config.compose import CONF_DIR, ConfigError
from mediated_transfer.reporting.__main__ import main as reporting_main
from mediated_transfer.provenance.judge import stale
from mediated_transfer.reporting.paper import paper_rows
from mediated_transfer.results import RunResult
from mediated_transfer.stored import codec

from .test_tracking import fresh_store

PAPER_TABLE = {"table2_rbf": "II", "table3_fsr": "III", "table4_dnn": "IV"}
SEEDS = 1  # per cell: every row of every table runs once (smoke scale has 2)

pytestmark = pytest.mark.slow


@pytest.fixture(scope="session")
def source_cache(tmp_path_factory) -> Path:
    """One source task cache for the whole session: each set is clustered once."""
    return tmp_path_factory.mktemp("source_task_cache")


@pytest.fixture
def root(tmp_path) -> Path:
    fresh_store(tmp_path)  # paths.mlflow_db = <root>/mlflow.db, already initialised
    return tmp_path


def _common(root: Path, cache: Path) -> list[str]:
    return ["scale=smoke", f"scale.seeds={SEEDS}", f"paths.root={root}", f"paths.cache_dir={cache}"]


def _run_cli(*args: str) -> None:
    """``python -m mediated_transfer ...`` in this process (jobs run in it with the basic launcher)."""
    GlobalHydra.instance().clear()
    saved = sys.argv
    try:
        sys.argv = ["mediated_transfer"]
        cli(list(args))
    finally:
        sys.argv = saved
        GlobalHydra.instance().clear()


def _results(sweep_dir: Path) -> dict[str, Path]:
    return {p.parent.relative_to(sweep_dir).as_posix(): p for p in sweep_dir.glob("*/seed=*/result.json")}


def _settings(root: Path) -> tracking.TrackingSettings:
    return tracking.TrackingSettings(f"sqlite:///{root / 'mlflow.db'}")


@pytest.mark.parametrize("experiment", sorted(PAPER_TABLE))
def test_experiment_runs_end_to_end_and_is_found_in_mlflow(root, source_cache, experiment):
    common = _common(root, source_cache)
    _run_cli(f"experiment={experiment}", "hydra/launcher=basic", *common)

    sweep_dir = root / "multirun" / experiment / "smoke"
    rows = paper_rows(PAPER_TABLE[experiment])
    expected = {f"{r.cell}/seed={s}" for r in rows for s in range(SEEDS)}
    assert set(_results(sweep_dir)) == expected

    assert reporting_main([f"experiment={experiment}", *common]) == 0
    figure = {"table2_rbf": "figure4_rbf", "table3_fsr": "figure5_fsr", "table4_dnn": "figure3_dnn"}[experiment]
    for name in (f"{experiment}.md", f"{experiment}.csv", f"{experiment}.tex", f"{figure}.png"):
        assert (root / "reports" / "smoke" / name).stat().st_size > 0
    assert f"| {SEEDS}/{SEEDS} |" in (root / "reports" / "smoke" / f"{experiment}.md").read_text()

    settings = _settings(root)
    runs = tracking.find_runs(settings, experiment, f"tags.kind = 'run' and tags.sweep = '{experiment}/smoke'")
    assert sorted(f"{r.data.tags['cell']}/seed={r.data.tags['seed']}" for r in runs) == sorted(expected)
    some = runs[0]
    assert "reward_loss" in some.data.metrics and some.data.params["scale.budget"] == "200"
    history = settings.client().get_metric_history(some.info.run_id, "mean_reward")
    assert sorted(m.step for m in history) == [100, 200]
    summaries = tracking.find_runs(settings, experiment, "tags.kind = 'cell_summary'")
    assert sorted(r.data.tags["cell"] for r in summaries) == sorted(r.cell for r in rows)


def test_interrupted_sweep_completes_on_rerun_without_recomputing_or_duplicating(root, source_cache):
    args = ["experiment=table2_rbf", "cell=none_0,scaffolded_15", *_common(root, source_cache), "scale.seeds=2"]
    sweep_dir = root / "multirun" / "table2_rbf" / "smoke"
    # The default launcher (joblib, 2 workers here), killed outright once a run has finished.
    process = subprocess.Popen([sys.executable, "-m", "mediated_transfer", "hydra.launcher.n_jobs=2", *args],
                               cwd=CONF_DIR.parent, start_new_session=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not _results(sweep_dir) and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
        _, stderr = process.communicate()
    before = {k: (p.stat().st_mtime_ns, p.read_text()) for k, p in _results(sweep_dir).items()}
    assert before, f"no run finished before the kill:\n{stderr}"

    _run_cli(*args, "hydra/launcher=basic")

    after = _results(sweep_dir)
    assert set(after) == {f"{c}/seed={s}" for c in ("none_0", "scaffolded_15") for s in range(2)}
    for key, (mtime, text) in before.items():  # finished runs were read back, not recomputed
        assert (after[key].stat().st_mtime_ns, after[key].read_text()) == (mtime, text)
    runs = tracking.find_runs(_settings(root), "table2_rbf", "tags.kind = 'run'")
    keys = [r.data.tags["run_key"] for r in runs]
    assert len(keys) == len(set(keys)) == 4
    assert all(r.info.status == "FINISHED" for r in runs)
    log = "".join(p.read_text() for p in sweep_dir.glob("*/seed=*/mediated_transfer.log"))
    assert re.search(r"\[table2_rbf/smoke \d/4(, ~\S+ left)?\] \w+ seed=\d: L_R=[\d.]+, [\d,]+ steps/s", log)


def test_single_run_is_skipped_when_its_result_exists(root, source_cache):
    args = ["strategy=regular", "n_source=15", "seed=1", *_common(root, source_cache)]
    _run_cli(*args)
    folder = root / "runs" / "linear_q_rbf" / "smoke" / "regular_15" / "seed=1"
    first = (folder / "result.json").stat().st_mtime_ns
    _run_cli(*args)
    assert (folder / "result.json").stat().st_mtime_ns == first
    assert "found, skipped" in (folder / "mediated_transfer.log").read_text()

    # An override that changes the run gets a folder of its own, and its config is recorded.
    _run_cli(*args, "algorithm.lambda_=0.5")
    variant = RunResult.read(folder / "algorithm.lambda_=0.5")
    assert variant.config["algorithm"]["lambda_"] == 0.5
    runs = tracking.find_runs(_settings(root), "linear_q_rbf", "tags.cell = 'regular_15'")
    assert len(runs) == 2


def test_a_folder_holding_another_configuration_is_refused(root, source_cache):
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose("config", overrides=[*_common(root, source_cache), "tracking=none"])
    folder = root / "run"
    run_job(cfg, folder)
    stored = json.loads((folder / "result.json").read_text())
    stored["config"]["algorithm"]["lambda_"] = 0.5
    stored["checksum"] = codec.checksum(stored)  # a genuine record of that other configuration
    (folder / "result.json").write_text(json.dumps(stored))
    with pytest.raises(ConfigError, match=rf"algorithm_params.lambda_: stored 0.5, now {cfg.algorithm.lambda_}"):
        run_job(cfg, folder)


def test_a_result_recorded_before_the_world_gained_a_key_is_the_same_run(root, source_cache):
    # result.json of a run made before env.move_frame existed: it ran the default (radial).
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose("config", overrides=[*_common(root, source_cache), "tracking=none"])
        tool = compose("config", overrides=[*_common(root, source_cache), "tracking=none", "env=tool_frame"])
    folder = root / "run"
    run_job(cfg, folder)
    stored = json.loads((folder / "result.json").read_text())
    del stored["config"]["env"]["move_frame"]
    stored["checksum"] = codec.checksum(stored)  # sealed as the committed runs are
    (folder / "result.json").write_text(json.dumps(stored))
    run_job(cfg, folder)  # found, not refused
    with pytest.raises(ConfigError, match="world.move_frame: stored 'radial', now 'tool'"):
        run_job(tool, folder)


def test_a_sweep_over_named_worlds_gives_each_its_own_folder(root, source_cache):
    _run_cli("-m", "env=default,goal_radius_1.5,tool_frame", "hydra/launcher=basic", "tracking=none",
             *_common(root, source_cache))
    sweep_dir = root / "multirun" / "linear_q_rbf" / "smoke"
    found = {p.parent.relative_to(sweep_dir).as_posix(): json.loads(p.read_text())["config"]["env"]
             for p in sweep_dir.glob("*/seed=*/*/result.json")}
    assert set(found) == {"none_0/seed=0/env=default", "none_0/seed=0/env=goal_radius_1.5",
                          "none_0/seed=0/env=tool_frame"}
    assert found["none_0/seed=0/env=goal_radius_1.5"]["goal_radius"] == 1.5
    assert found["none_0/seed=0/env=tool_frame"]["move_frame"] == "tool"


def test_submitit_local_launcher_runs_the_jobs(root, source_cache):
    result = subprocess.run(
        [sys.executable, "-m", "mediated_transfer", "experiment=table2_rbf", "hydra/launcher=submitit_local",
         "cell=regular_1", *_common(root, source_cache)],
        cwd=CONF_DIR.parent, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]
    sweep_dir = root / "multirun" / "table2_rbf" / "smoke"
    assert set(_results(sweep_dir)) == {"regular_1/seed=0"}
    assert list((sweep_dir / ".submitit").iterdir())  # the jobs went through submitit
    [run] = tracking.find_runs(_settings(root), "table2_rbf", "tags.kind = 'run'")
    assert run.data.tags["cell"] == "regular_1"


def test_a_sweep_over_any_n_source_runs(root, source_cache):
    # -m among the overrides, as README and docs/extending.md write it (not only first)
    _run_cli("strategy=regular,scaffolded", "-m", "n_source=7", "hydra/launcher=basic", "tracking=none",
             *_common(root, source_cache))
    sweep_dir = root / "multirun" / "linear_q_rbf" / "smoke"
    assert set(_results(sweep_dir)) == {"regular_7/seed=0", "scaffolded_7/seed=0"}
    result = RunResult.read(sweep_dir / "regular_7" / "seed=0")
    assert (result.strategy, result.n_source) == ("regular", 7)


def test_a_result_of_other_code_is_reported_stale_and_recomputed_on_request(root, source_cache, caplog):
    args = ["seed=1", "tracking=none", *_common(root, source_cache)]
    _run_cli(*args)
    folder = root / "runs" / "linear_q_rbf" / "smoke" / "none_0" / "seed=1"
    result = RunResult.read(folder)
    assert stale(result) is None and result.results_format == 2
    assert len(result.code["digest"]) == 16 and "commit" in result.code and "dirty" in result.code

    stored = json.loads((folder / "result.json").read_text())
    stored["code"] = {"commit": "0" * 40, "dirty": False, "digest": "0" * 16}  # as if older code wrote it
    stored["checksum"] = codec.checksum(stored)  # sealed as the committed runs are
    (folder / "result.json").write_text(json.dumps(stored))
    assert "computed by other code: commit 0000000000" in stale(RunResult.read(folder))
    _run_cli(*args)
    log = (folder / "mediated_transfer.log").read_text()
    assert "found, STALE (computed by other code" in log and "rerun_stale=true" in log
    assert RunResult.read(folder).code["digest"] == "0" * 16  # reused as it is, but not silently

    _run_cli(*args, "rerun_stale=true")
    assert stale(RunResult.read(folder)) is None  # recomputed by this code


def test_a_variant_sweep_is_reported_apart_from_the_baseline_and_compared_with_it(root, source_cache, capsys):
    from mediated_transfer.reporting.compare import main as compare_main

    common = [*_common(root, source_cache), "experiment=table2_rbf", "cell=none_0,regular_1"]
    _run_cli(*common, "hydra/launcher=basic")
    _run_cli(*common, "algorithm.lambda_=0.5", "hydra/launcher=basic")
    sweep_dir = root / "multirun" / "table2_rbf" / "smoke"
    variant = "algorithm.lambda_=0.5"
    assert set(_results(sweep_dir)) == {"none_0/seed=0", "regular_1/seed=0"}
    assert {p.parent.relative_to(sweep_dir).as_posix() for p in sweep_dir.glob(f"*/seed=*/{variant}/result.json")} \
        == {f"none_0/seed=0/{variant}", f"regular_1/seed=0/{variant}"}

    report_args = [a for a in common if not a.startswith("cell=")]
    assert reporting_main(report_args) == 0
    assert reporting_main([*report_args, variant]) == 0
    out = capsys.readouterr().out
    assert "table2_rbf: 2 runs -> " in out and f"table2_rbf [{variant}]: 2 runs -> " in out
    baseline_md = (root / "reports" / "smoke" / "table2_rbf.md").read_text()
    variant_md = (root / "reports" / "smoke" / "variants" / variant / "table2_rbf.md").read_text()
    assert variant not in baseline_md and f"`{variant}`" in variant_md
    for md, folder in ((baseline_md, ""), (variant_md, variant)):
        loss = RunResult.read(sweep_dir / "none_0" / "seed=0" / folder).reward_loss
        assert f"| without transfer | 0 | 1/1 | {loss:.2f} ± n/a |" in md  # exactly this sweep's run

    runs = tracking.find_runs(_settings(root), "table2_rbf", "tags.kind = 'run'")
    assert sorted(r.data.tags["variant"] for r in runs) == ["algorithm.lambda_=0.5"] * 2 + ["baseline"] * 2
    assert {r.info.run_name for r in runs if r.data.tags["variant"] != "baseline"} == {
        f"none_0/seed=0 [{variant}]", f"regular_1/seed=0 [{variant}]"}

    assert compare_main([*report_args, "--variant", variant]) == 0
    [table] = (root / "reports" / "smoke" / "compare").glob("*.md")
    text = table.read_text()
    assert "baseline" in text and variant in text
    assert list((root / "reports" / "smoke" / "compare").glob("*.png"))


def test_a_sweep_refuses_a_folder_of_another_configuration_before_any_run(root, source_cache):
    common = ["-m", "cell=none_0", "seed=0,1", "hydra/launcher=basic", "tracking=none", "experiment=table2_rbf",
              *_common(root, source_cache)]
    _run_cli(*common)
    sweep_dir = root / "multirun" / "table2_rbf" / "smoke"
    stored = json.loads((sweep_dir / "none_0" / "seed=1" / "result.json").read_text())
    stored["config"]["threshold"] = 7.0
    stored["checksum"] = codec.checksum(stored)  # a genuine record of that other configuration
    (sweep_dir / "none_0" / "seed=1" / "result.json").write_text(json.dumps(stored))
    untouched = (sweep_dir / "none_0" / "seed=0" / "result.json").stat().st_mtime_ns
    with pytest.raises(SystemExit) as error:
        _run_cli(*common)
    assert "holds a finished run of another configuration (threshold: stored 7.0" in str(error.value)
    assert "\n" not in str(error.value)
    assert (sweep_dir / "none_0" / "seed=0" / "result.json").stat().st_mtime_ns == untouched


def test_a_baseline_and_a_variant_sharing_a_sweep_folder_keep_their_own_plans(root, source_cache):
    from mediated_transfer.sweep.progress import sweep_progress
    from mediated_transfer.sweep import PLAN_PREFIX

    common = ["-m", "experiment=table2_rbf", "cell=none_0", "hydra/launcher=basic", "tracking=none",
              *_common(root, source_cache)]
    _run_cli(*common)
    _run_cli(*common, "algorithm.lambda_=0.5", "seed=0,1")
    sweep_dir = root / "multirun" / "table2_rbf" / "smoke"
    assert len(list(sweep_dir.glob(f"{PLAN_PREFIX}*.json"))) == 2
    assert sweep_progress(sweep_dir, "none_0/seed=0")[:2] == (1, 1)
    assert sweep_progress(sweep_dir, "none_0/seed=1/algorithm.lambda_=0.5")[:2] == (2, 2)


def test_progress_does_not_count_a_stale_result_being_recomputed(tmp_path):
    import os
    import time

    from mediated_transfer.sweep.progress import sweep_progress
    from mediated_transfer.sweep import write_plan

    runs = ["none_0/seed=0", "none_0/seed=1", "none_0/seed=2"]
    for run in runs[:2]:  # results from before the launch; seed=1's is stale
        (tmp_path / run).mkdir(parents=True)
        (tmp_path / run / "result.json").write_text("{}")
        os.utime(tmp_path / run / "result.json", (time.time() - 60, time.time() - 60))
    write_plan(tmp_path, runs, recompute=["none_0/seed=1"])
    assert sweep_progress(tmp_path, runs[0])[:2] == (1, 3)
    (tmp_path / runs[1] / "result.json").write_text("{}")  # recomputed
    assert sweep_progress(tmp_path, runs[0])[:2] == (2, 3)


@pytest.mark.parametrize("error, status", [(KeyboardInterrupt, "KILLED"), (RuntimeError, "FAILED")])
def test_a_run_stopped_while_computing_ends_its_mlflow_run_and_writes_nothing(root, source_cache, monkeypatch,
                                                                            error, status):
    from mediated_transfer import run as run_module

    real = run_module.execute_run

    def stopped_after_one_point(spec, **callbacks):
        def evaluated(*point):
            callbacks["on_evaluation"](*point)
            raise error("stopped")

        return real(spec, **{**callbacks, "on_evaluation": evaluated})

    monkeypatch.setattr(run_module, "execute_run", stopped_after_one_point)
    with pytest.raises((error, SystemExit)):
        _run_cli("-m", "experiment=table2_rbf", "cell=none_0", "seed=0", "hydra/launcher=basic",
                 *_common(root, source_cache))
    [run] = tracking.find_runs(_settings(root), "table2_rbf")
    assert run.info.status == status
    assert len(_settings(root).client().get_metric_history(run.info.run_id, "mean_reward")) == 1
    assert not _results(root / "multirun" / "table2_rbf" / "smoke")


def test_a_single_run_prints_its_current_reward(root, source_cache, capsys):
    _run_cli("cell=none_0", "seed=0", "tracking=none", *_common(root, source_cache))
    lines = [line for line in capsys.readouterr().out.splitlines() if "steps/s, <R>" in line]
    assert lines and lines[-1].endswith("(0% solved) at step 200, ~0m00s left")


def test_a_run_terminated_by_a_signal_ends_killed_in_mlflow(root, source_cache):
    """SIGTERM (a scheduler's kill or timeout) while a run computes: its MLflow run ends KILLED,
    with the points logged so far, and no result file is written."""
    import signal
    import subprocess
    import time

    command = [sys.executable, "-m", "mediated_transfer", "cell=none_0", "seed=0",
               *_common(root, source_cache), "scale.budget=4000000", "scale.eval_points=400"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 120
        while time.time() < deadline:
            runs = tracking.find_runs(_settings(root), "linear_q_rbf")
            if runs and _settings(root).client().get_metric_history(runs[0].info.run_id, "mean_reward"):
                break
            time.sleep(0.5)
        else:
            pytest.fail("the run logged no evaluation point within 120 s")
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=60) != 0
    finally:
        process.kill()
    [run] = tracking.find_runs(_settings(root), "linear_q_rbf")
    assert run.info.status == "KILLED"
    assert not list(root.rglob("result.json"))


def test_a_run_claimed_by_another_process_is_skipped_at_once(root, source_cache, capsys):
    """The same sweep launched twice: a run the other launch is computing is neither computed
    nor logged again (nor its MLflow run touched)."""
    from mediated_transfer.sweep.claim import claimed

    folder = root / "multirun" / "table2_rbf" / "smoke" / "none_0" / "seed=0"
    with claimed(folder) as mine:
        assert mine
        _run_cli("-m", "experiment=table2_rbf", "cell=none_0", "seed=0", "hydra/launcher=basic",
                 *_common(root, source_cache))
    assert "none_0 seed=0: being computed by another process, skipped" in capsys.readouterr().out
    assert not _results(root / "multirun" / "table2_rbf" / "smoke")
    assert not tracking.find_runs(_settings(root), "table2_rbf")


def _group(pgid: int) -> dict[int, str]:
    """The live processes of a process group: pid -> command line."""
    found = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            state, _, group = stat.read_text().rsplit(")", 1)[1].split()[:3]
            if int(group) == pgid and state != "Z":
                found[int(stat.parent.name)] = (stat.parent / "cmdline").read_text().replace("\0", " ")
        except (OSError, ValueError):
            pass  # ended meanwhile
    return found


# How a parallel sweep is stopped: (what is signalled, the signal), the launcher's exit status
# and the one line it ends with (None: it cannot say anything, it was SIGKILLed).
STOPS = {
    "launcher-SIGKILL": ("launcher", signal.SIGKILL, -9, None),
    "launcher-SIGTERM": ("launcher", signal.SIGTERM, 143, "interrupted (SIGTERM): 0 of 2 runs finished, 2 left"),
    "launcher-SIGINT": ("launcher", signal.SIGINT, 130, "interrupted (SIGINT): 0 of 2 runs finished, 2 left"),
    "ctrl-c": ("group", signal.SIGINT, 130, "interrupted (SIGINT): 0 of 2 runs finished, 2 left"),
    "worker-SIGKILL": ("worker", signal.SIGKILL, 1, "a worker process died ({SIGKILL(-9)}): 0 of 2 runs finished"),
}


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads processes from /proc (Linux)")
@pytest.mark.parametrize("stop", sorted(STOPS))
def test_a_stopped_parallel_sweep_leaves_no_process_and_no_running_mlflow_run(root, source_cache, tmp_path, stop):
    """A parallel sweep (2 loky workers) stopped while both runs compute: the workers and the
    pool's resource trackers are gone within seconds (an orphaned worker watches its launcher),
    every MLflow run ends KILLED (before the launcher exits, where it lives on to see to it),
    nothing is written, and the launcher ends with one line, no traceback."""
    target, signum, status, line = STOPS[stop]
    command = [sys.executable, "-m", "mediated_transfer", "-m", "cell=none_0", "seed=0,1", "hydra.launcher.n_jobs=2",
               *_common(root, source_cache), "scale.budget=4000000", "scale.eval_points=400"]
    stderr = tmp_path / "stderr.txt"
    with open(stderr, "w") as err:
        launcher = subprocess.Popen(command, cwd=CONF_DIR.parent, start_new_session=True,
                                    stdout=subprocess.DEVNULL, stderr=err)
    client = _settings(root).client()
    try:
        deadline = time.time() + 180
        while launcher.poll() is None and time.time() < deadline:
            runs = tracking.find_runs(_settings(root), "linear_q_rbf")
            if len(runs) == 2 and all(client.get_metric_history(r.info.run_id, "mean_reward") for r in runs):
                break
            time.sleep(0.5)
        else:
            pytest.fail(f"the runs did not both compute within 180 s:\n{stderr.read_text()[-3000:]}")
        if target == "launcher":
            launcher.send_signal(signum)
        elif target == "group":  # a terminal's Ctrl-C reaches every process of its foreground group
            os.killpg(launcher.pid, signum)
        else:
            [worker, *_] = [pid for pid, cmd in _group(launcher.pid).items() if "loky" in cmd and "resource_tracker" not in cmd]
            os.kill(worker, signum)
        assert launcher.wait(timeout=60) == status
        at_exit = [r.info.status for r in tracking.find_runs(_settings(root), "linear_q_rbf")]
        deadline = time.time() + 20  # the launcher's workers and resource trackers
        while _group(launcher.pid) and time.time() < deadline:
            time.sleep(0.2)
        assert not _group(launcher.pid), f"still alive 20 s after the launcher: {_group(launcher.pid)}"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(launcher.pid, signal.SIGKILL)  # whatever happened
    runs = tracking.find_runs(_settings(root), "linear_q_rbf")
    assert [r.info.status for r in runs] == ["KILLED", "KILLED"]
    if line is not None:
        assert at_exit == ["KILLED", "KILLED"]
        text = stderr.read_text()
        assert text.splitlines()[-1].startswith(line) and "Traceback" not in text
        assert text.splitlines()[-1].endswith("run the same command to resume (finished runs are kept)")
    assert not list(root.rglob("result.json"))


def test_a_run_interrupted_while_its_written_result_is_logged_ends_finished(root, source_cache, monkeypatch, capsys):
    """Ctrl-C after the result is written, while it is logged to MLflow: the run is logged in
    full and ends FINISHED (not RUNNING), and the command ends with one line, status 130."""
    interrupted = []
    real = tracking._log_artifacts

    def ctrl_c_once(client, run_id, artifacts):
        if not interrupted:
            interrupted.append(run_id)
            os.kill(os.getpid(), signal.SIGINT)  # a real Ctrl-C, delivered on the next bytecode
            time.sleep(1)
        return real(client, run_id, artifacts)

    monkeypatch.setattr(tracking, "_log_artifacts", ctrl_c_once)
    try:
        _run_cli("-m", "experiment=table2_rbf", "cell=none_0", "seed=0", "hydra/launcher=basic",
                 *_common(root, source_cache))
    except KeyboardInterrupt:  # would stop pytest itself
        pytest.fail("Ctrl-C came out of the command as a KeyboardInterrupt (a traceback)")
    except SystemExit as stopped:
        assert stopped.code == 130 and interrupted
    else:
        pytest.fail("the command was not interrupted")
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith("interrupted (SIGINT): 1 of 1 runs finished")
    [run] = tracking.find_runs(_settings(root), "table2_rbf")
    assert run.info.status == "FINISHED" and "reward_loss" in run.data.metrics
    assert {a.path for a in _settings(root).client().list_artifacts(run.info.run_id)} >= {"result.json", "curve.csv"}


def test_a_run_started_in_the_background_finishes_after_its_shell_exits(root, source_cache):
    """`nohup python -m mediated_transfer ... &` from a shell that exits while the run computes:
    the run is re-parented and goes on to the end (only a pool's worker watches its launcher)."""
    command = " ".join([sys.executable, "-m", "mediated_transfer", "cell=none_0", "seed=0",
                        *_common(root, source_cache), "scale.budget=60000", "scale.eval_points=20"])
    shell = subprocess.Popen(["bash", "-c", f"{command} >/dev/null 2>&1 & echo $! && sleep 600"],
                             cwd=CONF_DIR.parent, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    run_pid = int(shell.stdout.readline())
    try:
        deadline = time.time() + 120
        while not tracking.find_runs(_settings(root), "linear_q_rbf") and time.time() < deadline:
            time.sleep(0.5)
        shell.kill()  # the shell is gone while the run computes
        shell.wait()
        assert not list((root / "runs").rglob("result.json")), "the run ended before its shell: a longer budget"
        deadline = time.time() + 300
        while time.time() < deadline:
            try:
                os.kill(run_pid, 0)
            except ProcessLookupError:
                break
            time.sleep(0.2)
        else:
            pytest.fail("the run did not end")
    finally:
        try:
            os.kill(run_pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    [result] = (root / "runs").rglob("result.json")
    assert RunResult.read(result.parent).steps[-1] == 60000
    [run] = tracking.find_runs(_settings(root), "linear_q_rbf")
    assert run.info.status == "FINISHED"


@pytest.mark.parametrize("sweep", [False, True])
def test_an_unreachable_tracking_server_stops_the_command_at_once_in_one_line(tmp_path, sweep):
    import time

    start = time.perf_counter()
    with pytest.raises(SystemExit) as error:
        _run_cli(*(["-m", "experiment=table2_rbf", "cell=none_0", "hydra/launcher=basic"] if sweep else []),
                 "scale=smoke", f"paths.root={tmp_path}", "tracking=server", "tracking.uri=http://127.0.0.1:9")
    assert str(error.value).startswith("Could not prepare the runs: ") and "\n" not in str(error.value)
    assert time.perf_counter() - start < 60  # MLflow's own retries would take minutes
    assert not list(tmp_path.iterdir())


SHARE_GROUP, SHARE_USERS = "mt-share", ("mt-share-a", "mt-share-b")


def _as_user(user: str, args: list[str], home: Path) -> subprocess.CompletedProcess:
    """``python *args`` as ``user`` of SHARE_GROUP, umask 002. It may read
    everything (CAP_DAC_READ_SEARCH: this interpreter may live in root's 0700 home) and write
    only what the user may, which is what is tested."""
    command = ["setpriv", f"--reuid={user}", f"--regid={SHARE_GROUP}", "--init-groups",
               "--inh-caps=+dac_read_search", "--ambient-caps=+dac_read_search",
               sys.executable, *args]
    return subprocess.run(command, cwd=CONF_DIR.parent, env={**os.environ, "HOME": str(home)}, umask=0o002,
                          capture_output=True, text=True, timeout=600)


def _shared_users() -> str | None:
    """Create SHARE_GROUP and SHARE_USERS if missing (kept: other test sessions may use them);
    why not, if they cannot be."""
    import shutil

    if os.geteuid() != 0:
        return "creates a group and two users: needs root"
    missing = [tool for tool in ("groupadd", "useradd", "setpriv", "getent") if shutil.which(tool) is None]
    if missing:
        return f"needs {', '.join(missing)}"
    subprocess.run(["groupadd", "-f", SHARE_GROUP], check=True, capture_output=True)
    for user in SHARE_USERS:
        if subprocess.run(["getent", "passwd", user], capture_output=True).returncode != 0:
            # 9: made meanwhile by another session
            added = subprocess.run(["useradd", "-M", "-N", "-g", SHARE_GROUP, "-s", "/usr/sbin/nologin", user],
                                   capture_output=True, text=True)
            if added.returncode not in (0, 9):
                return f"useradd {user}: {added.stderr.strip()}"
    probe = _as_user(SHARE_USERS[0], ["-c", "import mediated_transfer.app"], Path("/tmp"))
    if probe.returncode != 0:
        return f"cannot run the package as {SHARE_USERS[0]} with setpriv: {probe.stderr.strip()[-300:]}"
    # MLflow's store migrations look for their scripts with os.access, which ignores the read
    # capability: the environment itself must be readable by the group, as a shared one is.
    reach = _as_user(SHARE_USERS[0], ["-c", _REACH_MIGRATIONS], Path("/tmp"))
    if reach.returncode != 0:
        last = (reach.stderr.strip().splitlines() or [""])[-1]
        return (f"{SHARE_USERS[0]} cannot reach this environment's files (a folder on the path of "
                f"{sys.prefix} is not readable by others, e.g. mktemp's 0700): {last}")
    return None


_REACH_MIGRATIONS = """
import os, mlflow.store
migrations = os.path.join(os.path.dirname(mlflow.store.__file__), "db_migrations")
assert os.access(migrations, os.R_OK | os.X_OK), migrations
"""


def test_two_users_of_one_group_share_a_sweep_and_its_store():
    """A collaborator in the same group (umask 002) runs the same sweep, in the same folder and
    MLflow store, after the first: it finds the first's runs, computes its own, and the files a
    sweep creates (claims, the store's lock, the SQLite store) are group-writable like results."""
    import shutil
    import stat
    import tempfile

    reason = _shared_users()
    if reason is not None:
        pytest.skip(reason)
    shared = Path(tempfile.mkdtemp(prefix="mt-share-"))  # not under pytest's 0700 folders
    try:
        shutil.chown(shared, group=SHARE_GROUP)
        shared.chmod(0o2775)  # a group's folder: what is made in it belongs to the group
        common = ["-m", "mediated_transfer", "-m", "cell=none_0", "hydra/launcher=basic", "scale=smoke",
                  f"paths.root={shared}", f"paths.cache_dir={shared / 'cache'}"]
        for user, seeds in zip(SHARE_USERS, ("seed=0,1", "seed=0,1,2")):
            done = _as_user(user, [*common, seeds], shared)
            assert done.returncode == 0, f"{user}: {done.stderr[-3000:]}"
        sweep_dir = shared / "multirun" / "linear_q_rbf" / "smoke"
        assert set(_results(sweep_dir)) == {f"none_0/seed={s}" for s in range(3)}
        made = [shared / "mlflow.db", shared / "mlflow.db.lock", *sweep_dir.glob("*/seed=*/.claim")]
        assert len(made) == 5
        assert {p.relative_to(shared).as_posix(): oct(stat.S_IMODE(p.stat().st_mode)) for p in made} == {
            p.relative_to(shared).as_posix(): "0o664" for p in made}
        assert (sweep_dir / "none_0" / "seed=2" / ".claim").owner() == SHARE_USERS[1]
        runs = tracking.find_runs(_settings(shared), "linear_q_rbf", "tags.kind = 'run'")
        assert sorted(r.data.tags["seed"] for r in runs) == ["0", "1", "2"]
        assert all(r.info.status == "FINISHED" for r in runs)
    finally:
        shutil.rmtree(shared, ignore_errors=True)


def test_a_finished_and_logged_sweep_is_answered_without_launching_it(root, source_cache, capsys):
    """Run again, a sweep whose every run is finished and in MLflow prints its runs' lines from
    the stored results (sweep/answered.py): Hydra launches nothing, MLflow is only read."""
    args = ["-m", "experiment=table2_rbf", "cell=none_0", *_common(root, source_cache)]
    _run_cli(*args, "hydra/launcher=basic")
    sweep_dir = root / "multirun" / "table2_rbf" / "smoke"
    launched = (sweep_dir / "multirun.yaml").stat().st_mtime_ns
    settings = _settings(root)
    logged = sorted(r.info.run_id for r in tracking.find_runs(settings, "table2_rbf"))
    assert len(logged) == SEEDS

    capsys.readouterr()
    _run_cli(*args)
    lines = re.findall(r"(\[table2_rbf/smoke .*, found, skipped)$", capsys.readouterr().out, re.MULTILINE)
    assert lines == [f"[table2_rbf/smoke {SEEDS}/{SEEDS}] none_0 seed={s}: L_R="
                     f"{RunResult.read(sweep_dir / 'none_0' / f'seed={s}').reward_loss:.2f}, found, skipped"
                     for s in range(SEEDS)]
    assert (sweep_dir / "multirun.yaml").stat().st_mtime_ns == launched  # Hydra did not launch
    assert sorted(r.info.run_id for r in tracking.find_runs(settings, "table2_rbf")) == logged

    # A run missing from MLflow is not answered for: the sweep's job logs it again.
    settings.client().delete_run(logged[0])
    _run_cli(*args)
    assert (sweep_dir / "multirun.yaml").stat().st_mtime_ns != launched
    again = tracking.find_runs(settings, "table2_rbf")
    assert len(again) == SEEDS and all(r.info.status == "FINISHED" for r in again)
