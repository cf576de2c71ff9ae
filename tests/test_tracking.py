"""MLflow tracking: what a learning run logs, that logging twice never duplicates, that a run
left unfinished by an interruption is redone, and that parallel workers can share the SQLite
store once it has been prepared."""

from __future__ import annotations

import math
import multiprocessing
import shutil
from pathlib import Path

import pytest

from mediated_transfer.sweep import tracking
from mediated_transfer.results import RunResult

_TEMPLATE: dict[str, Path] = {}


def fresh_store(folder: Path) -> str:
    """A SQLite tracking URI in ``folder``, copied from an empty store made once per session
    (creating MLflow's tables takes seconds; copying the file does not)."""
    if "db" not in _TEMPLATE:
        import tempfile

        template = Path(tempfile.mkdtemp(prefix="mlflow-template-")) / "mlflow.db"
        tracking.TrackingSettings(f"sqlite:///{template}").client().search_experiments()
        _TEMPLATE["db"] = template
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(_TEMPLATE["db"], folder / "mlflow.db")
    return f"sqlite:///{folder / 'mlflow.db'}"


def synthetic_result(strategy="regular", n_source=15, seed=0, curve=(2.0, 6.0, 9.0), steps=(100, 200, 300),
                     algorithm="linear_q", representation="rbf") -> RunResult:
    from mediated_transfer.metrics import reward_loss, time_to_threshold
    from mediated_transfer.provenance import RESULTS_FORMAT, code_version
    from mediated_transfer.run import RunSpec

    return RunResult(
        algorithm=algorithm, representation=representation, strategy=strategy, n_source=n_source,
        seed=seed, budget=steps[-1], steps=list(steps), mean_reward=list(curve),
        success_rate=[c / 10 for c in curve], reward_loss=reward_loss(curve),
        time_to_threshold=time_to_threshold(steps, curve), source_phase_end=None,
        source_tasks_solved=0, wall_time_s=1.5, learning_steps_per_s=200.0,
        learner_stats={"episodes": 7.0}, results_format=RESULTS_FORMAT,
        code=code_version(RunSpec(algorithm=algorithm, representation=representation, strategy=strategy,
                                  n_source=n_source)),
    )


@pytest.fixture
def settings(tmp_path) -> tracking.TrackingSettings:
    return tracking.TrackingSettings(fresh_store(tmp_path), str(tmp_path / "artifacts"))


def _log(settings, result, key="multirun/t/quick/regular_15/seed=0@abc", artifacts=()):
    return tracking.log_run(settings, "table_x", key=key, run_name="regular_15/seed=0", result=result,
                            params={"algorithm.lambda_": "0.75", "seed": "0"},
                            tags={"table": "table_x", "cell": "regular_15", "sweep": "table_x/quick"},
                            artifacts=artifacts)


def test_a_run_logs_config_curve_metrics_and_tags(settings, tmp_path):
    result = synthetic_result()
    artifact = tmp_path / "curve.csv"
    artifact.write_text("step,mean_reward\n")
    run_id = _log(settings, result, artifacts=[artifact])

    [run] = tracking.find_runs(settings, "table_x", "tags.cell = 'regular_15' and tags.sweep = 'table_x/quick'")
    assert run.info.run_id == run_id and run.info.status == "FINISHED"
    assert run.data.params == {"algorithm.lambda_": "0.75", "seed": "0"}
    assert run.data.metrics["reward_loss"] == pytest.approx(result.reward_loss)
    assert run.data.metrics["time_to_threshold"] == 300
    assert run.data.tags["kind"] == tracking.KIND_RUN
    history = settings.client().get_metric_history(run_id, "mean_reward")
    assert sorted((m.step, m.value) for m in history) == [(100, 2.0), (200, 6.0), (300, 9.0)]
    assert [a.path for a in settings.client().list_artifacts(run_id)] == ["curve.csv"]


def test_never_reaching_the_threshold_logs_the_budget_for_a_sort_and_a_tag_that_says_never(settings):
    _log(settings, synthetic_result(curve=(1.0, 2.0, 3.0)))  # never reaches 8
    _log(settings, synthetic_result(seed=1, curve=(2.0, 9.0, 9.0)), key="multirun/t/quick/regular_15/seed=1@abc")
    runs = {r.data.tags.get("time_to_threshold", "reached"): r for r in tracking.find_runs(settings, "table_x")}
    assert runs[tracking.NEVER].data.metrics["time_to_threshold"] == 300  # the budget
    assert runs["reached"].data.metrics["time_to_threshold"] == 200
    assert runs[tracking.NEVER].data.metrics["reward_loss"] > runs["reached"].data.metrics["reward_loss"]


def test_logging_the_same_run_again_does_not_duplicate_it(settings):
    first = _log(settings, synthetic_result())
    assert _log(settings, synthetic_result()) == first
    _log(settings, synthetic_result(seed=1), key="multirun/t/quick/regular_15/seed=1@abc")
    assert len(tracking.find_runs(settings, "table_x")) == 2


def test_a_run_interrupted_while_logging_is_logged_again(settings):
    key = "multirun/t/quick/regular_15/seed=0@abc"
    client = settings.client()
    experiment_id = tracking.prepare(settings, "table_x")
    # What a kill between create_run and set_terminated leaves behind.
    partial = client.create_run(experiment_id, tags={"run_key": key, "run_key_hash": tracking.key_hash(key)})
    run_id = _log(settings, synthetic_result(), key=key)
    runs = tracking.find_runs(settings, "table_x")
    assert [r.info.run_id for r in runs] == [run_id] != [partial.info.run_id]
    assert runs[0].info.status == "FINISHED"


def test_summary_is_replaced_when_its_data_changes(settings, tmp_path):
    from mediated_transfer.metrics import summarise_runs

    summary = summarise_runs([[2.0, 9.0], [4.0, 9.0]], [100, 200])
    kwargs = dict(key="summary/table_x/quick/regular_15", run_name="regular_15 (summary)",
                  summary=summary, tags={"table": "table_x", "cell": "regular_15"})
    first = tracking.log_summary(settings, "table_x", fingerprint="a", **kwargs)
    assert tracking.log_summary(settings, "table_x", fingerprint="a", **kwargs) == first
    second = tracking.log_summary(settings, "table_x", fingerprint="b", **kwargs)
    [run] = tracking.find_runs(settings, "table_x", f"tags.kind = '{tracking.KIND_SUMMARY}'")
    assert run.info.run_id == second != first
    assert run.data.metrics["reward_loss_mean"] == pytest.approx(summary["reward_loss_mean"])
    assert run.data.metrics["time_to_threshold"] == 200


def test_summary_of_a_single_run_logs_its_undefined_sem_as_nan(settings):
    from mediated_transfer.metrics import summarise_runs

    tracking.log_summary(settings, "table_x", key="s", run_name="s", tags={}, fingerprint="a",
                         summary=summarise_runs([[2.0, 9.0]], [100, 200]))
    [run] = tracking.find_runs(settings, "table_x")
    assert math.isnan(run.data.metrics["reward_loss_sem"])
    assert run.data.metrics["n_runs"] == 1


# --- a cell's summary is the parent of its runs ------------------------------------------------
CELL = {"table": "table_x", "cell": "regular_15", "sweep": "table_x/quick", "variant": "baseline"}


def _cell_run(settings, seed, variant="baseline"):
    where = "" if variant == "baseline" else f"/{variant}"
    return tracking.log_run(settings, "table_x", key=f"multirun/t/quick/regular_15/seed={seed}{where}@abc",
                            run_name=f"regular_15/seed={seed}", result=synthetic_result(seed=seed), params={},
                            tags={**CELL, "seed": str(seed), "variant": variant})


def _cell_summary(settings, fingerprint, curves=((2.0, 9.0), (4.0, 9.0))):
    from mediated_transfer.metrics import summarise_runs

    return tracking.log_summary(settings, "table_x", key="summary/table_x/quick/regular_15",
                                run_name="regular_15 (summary, baseline)", tags=CELL, fingerprint=fingerprint,
                                summary=summarise_runs([list(c) for c in curves], [100, 200]))


def _parent(settings, run_id):
    return settings.client().get_run(run_id).data.tags.get(tracking.PARENT)


def test_a_cells_summary_is_the_parent_of_its_runs_and_of_those_logged_after_it(settings):
    before = [_cell_run(settings, seed) for seed in (0, 1)]
    variant = _cell_run(settings, 0, variant="algorithm.lambda_=0.5")
    summary = _cell_summary(settings, "a")
    assert [_parent(settings, r) for r in before] == [summary, summary]
    assert _parent(settings, variant) is None  # a variant's runs belong to the variant's cell
    assert _parent(settings, _cell_run(settings, 2)) == summary
    live = tracking.LiveRun(settings, "table_x", key="multirun/t/quick/regular_15/seed=3@abc",
                            run_name="regular_15/seed=3", params={}, tags={**CELL, "seed": "3"})
    assert _parent(settings, live.run_id) == summary


def test_a_replaced_summary_hands_its_runs_to_the_new_one(settings):
    runs = [_cell_run(settings, seed) for seed in (0, 1)]
    old = _cell_summary(settings, "a")
    new = _cell_summary(settings, "b")
    assert new != old and settings.client().get_run(old).info.lifecycle_stage == "deleted"
    assert [_parent(settings, r) for r in runs] == [new, new]


def test_a_summary_shares_its_runs_columns_l_r_and_time_to_threshold(settings):
    _cell_summary(settings, "a")
    [reached] = tracking.find_runs(settings, "table_x")
    assert reached.data.metrics["reward_loss"] == reached.data.metrics["reward_loss_mean"]
    assert reached.data.metrics["time_to_threshold"] == 200 and "time_to_threshold" not in reached.data.tags
    _cell_summary(settings, "b", curves=((1.0, 2.0), (1.0, 3.0)))  # the mean curve never reaches 8
    [never] = tracking.find_runs(settings, "table_x")
    assert never.data.metrics["time_to_threshold"] == 200 and never.data.tags["time_to_threshold"] == tracking.NEVER


def test_params_leave_out_where_outputs_go_and_how_runs_are_scheduled():
    from omegaconf import OmegaConf

    from mediated_transfer.config.compose import compose_config

    config = OmegaConf.to_container(compose_config(["experiment=table2_rbf", "cell=regular_15"]), resolve=True)
    params = tracking.flatten(config)
    assert {"seed", "cell", "algorithm.lambda_", "representation.name", "scale.budget", "env.goal_radius"} <= set(params)
    assert not any(k.split(".")[0] in {"paths", "tracking"} for k in params)
    every = tracking.flatten(config, leave_out=frozenset())
    # Every key left out is one the config has (or a group of them).
    assert all(any(k == out or k.startswith(f"{out}.") for k in every) for out in tracking.NOT_PARAMS)
    assert len(params) < len(every) - 10


def test_each_experiment_stores_a_runs_view_with_l_r_and_time_to_threshold_as_columns(settings):
    import json

    experiment_id = tracking.prepare(settings, "table_x")
    tags = settings.client().get_experiment(experiment_id).tags
    view = json.loads(tags[f"mlflow.sharedViewState.{tracking.RUNS_VIEW}"])
    assert {"metrics.`reward_loss`", "metrics.`time_to_threshold`"} <= set(view["selectedColumns"])


def test_l_r_is_logged_as_the_ui_shows_it(settings):
    result = synthetic_result(curve=(2.1, 6.1, 9.1))  # a float sum: 2.1 + ... leaves 1e-15s
    _log(settings, result)
    [run] = tracking.find_runs(settings, "table_x")
    assert run.data.metrics["reward_loss"] == round(result.reward_loss, 9)


def test_missing_server_uri_is_a_clear_error():
    with pytest.raises(ValueError, match="tracking.uri"):
        tracking.TrackingSettings.from_config({"enabled": True, "uri": None})


def test_flatten_gives_dotted_string_params():
    assert tracking.flatten({"algorithm": {"lambda_": 0.8, "name": "linear_q"}, "seed": 3}) == {
        "algorithm.lambda_": "0.8", "algorithm.name": "linear_q", "seed": "3"}


def _worker(args):
    uri, seed = args
    settings = tracking.TrackingSettings(uri)
    for i in range(3):
        tracking.log_run(settings, "table_x", key=f"k/{seed}/{i}", run_name=f"{seed}/{i}",
                         result=synthetic_result(seed=seed), params={"seed": str(seed)}, tags={})
    return seed


@pytest.mark.slow
def test_parallel_workers_share_a_prepared_sqlite_store(tmp_path):
    uri = fresh_store(tmp_path)
    tracking.prepare(tracking.TrackingSettings(uri), "table_x")
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        assert sorted(pool.map(_worker, [(uri, 0), (uri, 1)])) == [0, 1]
    runs = tracking.find_runs(tracking.TrackingSettings(uri), "table_x")
    assert sorted(r.data.tags["run_key"] for r in runs) == sorted(f"k/{s}/{i}" for s in (0, 1) for i in range(3))


# --- runs followed live -------------------------------------------------------------------------
def _live(settings, key="multirun/t/quick/none_0/seed=0@abc"):
    return tracking.LiveRun(settings, "table_x", key=key, run_name="none_0/seed=0",
                            params={"seed": "0"}, tags={"table": "table_x", "cell": "none_0"})


def test_a_live_run_shows_each_point_while_it_runs_with_its_wall_clock_time(settings):
    import time

    live = _live(settings)
    client = settings.client()
    for step, reward in [(100, 1.0), (200, 4.0), (300, 9.0)]:
        time.sleep(0.01)
        live.evaluation(step, reward, reward / 10)
        run = client.get_run(live.run_id)
        assert run.info.status == "RUNNING"
        history = client.get_metric_history(live.run_id, "mean_reward")
        assert [m.step for m in history] == [s for s in (100, 200, 300) if s <= step]
    stamps = [m.timestamp for m in history]
    assert stamps == sorted(stamps) and len(set(stamps)) == 3 and min(stamps) >= run.info.start_time > 0
    run_id = live.run_id
    live.finish(synthetic_result(curve=(1.0, 4.0, 9.0)))
    finished = client.get_run(run_id)
    assert finished.info.status == "FINISHED" and finished.info.end_time >= max(stamps)
    assert finished.data.metrics["reward_loss"] == pytest.approx(synthetic_result(curve=(1.0, 4.0, 9.0)).reward_loss)
    assert finished.data.tags["mlflow.source.git.commit"]
    # Logging the same run again from its files finds it: no duplicate.
    assert _log(settings, synthetic_result(), key="multirun/t/quick/none_0/seed=0@abc") == run_id


@pytest.mark.parametrize("status", ["KILLED", "FAILED"])
def test_a_live_run_that_stops_early_is_not_left_running(settings, status):
    live = _live(settings)
    live.evaluation(100, 1.0, 0.1)
    run_id = live.run_id
    live.end(status)
    assert settings.client().get_run(run_id).info.status == status
    # A rerun deletes it and follows the new run.
    again = _live(settings)
    assert again.run_id != run_id
    assert settings.client().get_run(run_id).info.lifecycle_stage == "deleted"



def test_ctrl_c_during_a_store_write_takes_effect_after_it_so_the_run_still_ends_at_once(settings, monkeypatch):
    """A Ctrl-C arriving inside a store write is held until the write ends: interrupted half-way,
    SQLite would keep this process's lock, and ending the run KILLED would wait 20 s and fail."""
    import os
    import signal
    import time

    live = _live(settings)
    real = live.client.log_batch
    inside = []

    def interrupted_write(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)  # a real Ctrl-C, delivered on the next bytecode
        time.sleep(0.05)
        inside.append(real(*args, **kwargs))  # reached only if the signal was held back

    monkeypatch.setattr(live.client, "log_batch", interrupted_write)
    with pytest.raises(KeyboardInterrupt):
        live.evaluation(100, 1.0, 0.1)
    assert inside  # the write finished before the interrupt was raised
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    run_id, started = live.run_id, time.monotonic()
    live.end("KILLED")
    assert time.monotonic() - started < 5
    client = settings.client()
    assert client.get_run(run_id).info.status == "KILLED"
    assert [m.step for m in client.get_metric_history(run_id, "mean_reward")] == [100]

def test_the_ui_links_open_each_experiments_runs(settings):
    experiment_id = tracking.prepare(settings, "table_y")
    assert tracking.runs_view_links(settings, "http://127.0.0.1:5000/") == [
        f"table_y: http://127.0.0.1:5000/#/experiments/{experiment_id}/runs?viewStateShareKey={tracking.RUNS_VIEW}"]


def _prepare(args):
    uri, name = args
    return tracking.prepare(tracking.TrackingSettings(uri), name)


@pytest.mark.slow
def test_two_sweeps_starting_together_on_a_new_store_both_prepare_it(tmp_path):
    uri = f"sqlite:///{tmp_path / 'new' / 'mlflow.db'}"
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        ids = pool.map(_prepare, [(uri, "table_a"), (uri, "table_b")])
    assert len(set(ids)) == 2
    names = {e.name for e in tracking.TrackingSettings(uri).client().search_experiments()}
    assert {"table_a", "table_b"} <= names


def test_a_run_interrupted_while_logged_from_its_files_is_not_left_running(settings, monkeypatch):
    key = "multirun/t/quick/regular_15/seed=0@abc"
    client_type = type(settings.client())

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(client_type, "log_artifact", interrupted)
    with pytest.raises(KeyboardInterrupt):
        _log(settings, synthetic_result(), key=key, artifacts=[Path(__file__)])
    [run] = tracking.find_runs(settings, "table_x")
    assert run.info.status == "KILLED"
    monkeypatch.undo()
    run_id = _log(settings, synthetic_result(), key=key)  # the rerun replaces it
    assert [r.info.run_id for r in tracking.find_runs(settings, "table_x")] == [run_id]


def test_a_store_failing_during_a_run_stops_following_it_but_not_the_run(settings, monkeypatch):
    live = _live(settings)
    live.evaluation(100, 1.0, 0.1)
    client_type = type(live.client)

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(client_type, "log_batch", broken)
    with pytest.warns(RuntimeWarning, match="MLflow stopped following this run.*disk full"):
        live.evaluation(200, 2.0, 0.2)
    live.evaluation(300, 3.0, 0.3)  # silently nothing: following has stopped
    live.finish(synthetic_result())


def test_the_sqlite_store_and_its_lock_follow_the_umask_so_that_a_group_can_share_them(tmp_path):
    """SQLite creates its file 0644 whatever the umask (and its journals take that mode): a
    collaborator of the group could not log into a store the other one created."""
    import os
    import stat

    db = tmp_path / "store" / "mlflow.db"
    previous = os.umask(0o002)
    try:
        tracking.prepare(tracking.TrackingSettings(f"sqlite:///{db}"), experiment="table_x")
    finally:
        os.umask(previous)
    for path in (db, db.with_name("mlflow.db.lock")):
        assert stat.S_IMODE(path.stat().st_mode) == 0o664, path
    assert tracking.TrackingSettings(f"sqlite:///{db}").client().get_experiment_by_name("table_x") is not None
