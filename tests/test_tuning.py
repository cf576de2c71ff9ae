"""The tuning protocol (issue 9) end to end at smoke scale, in a temporary folder: a two-trial
search stores its study with the provisional defaults as trial 0, resumes to exactly the new
trial count, redoes a trial whose worker died, logs every trial as an MLflow run nested under
the study's, exports trials.csv, and Table I builds from it; a bad search-space file is refused
in one line naming the key."""

from __future__ import annotations

import dataclasses
import re
import time
from pathlib import Path

import optuna
import pandas as pd
import pytest

from mediated_transfer.sweep import tracking
from mediated_transfer.results import RunResult
from mediated_transfer.tuning import mlflow_log, study as study_module
from mediated_transfer.tuning.__main__ import main as tune
from mediated_transfer.tuning.objective import first_step_at_threshold, trial_record
from mediated_transfer.tuning.sampler import TrialSeededRandomSampler
from mediated_transfer.tuning.space import SEARCH_SPACE_DIR, SearchSpaceError, find_search_space, load_search_space
from mediated_transfer.tuning.study import StudyPlan, load_study, study_folder
from mediated_transfer.tuning.table1 import main as table1

from .test_tracking import fresh_store

SMOKE = ["--scale", "smoke"]


@pytest.fixture(scope="module")
def space():
    """The RBF search space at smoke scale (loading composes a config: done once)."""
    return find_search_space("rbf").with_scale("smoke")


def _study(space, root: Path) -> optuna.Study:
    return load_study(StudyPlan(space, study_folder(root, space), trials=1))


def _complete(space, root: Path) -> list:
    return _study(space, root).get_trials(states=(optuna.trial.TrialState.COMPLETE,))


@pytest.mark.slow
def test_search_stores_resumes_tracks_exports_and_builds_table1(space, tmp_path, capsys):
    fresh_store(tmp_path)  # <root>/mlflow.db, its tables already made (that takes seconds)
    assert tune(["rbf", *SMOKE, "--trials", "2", "--root", str(tmp_path)]) == 0
    folder = tmp_path / "tuning" / "rbf" / "smoke"
    assert (folder / "study.db").is_file()
    first = _complete(space, tmp_path)
    assert [t.number for t in first] == [0, 1]
    assert first[0].user_attrs["role"] == "defaults" and first[0].params == space.defaults
    assert first[1].user_attrs["role"] == "random"
    record = first[1].user_attrs
    assert record["seeds"] == [1000, 1001, 1002] and len(record["reward_loss"]) == 3
    assert first[1].value == pytest.approx(sum(record["reward_loss"]) / 3)
    assert re.search(r"\[rbf/smoke 2/2, ~\S+ left\] trial 1 \(random\): L_R [\d.]+ .*best [\d.]+ "
                     r"\(trial \d\), defaults [\d.]+", capsys.readouterr().out)

    # Resumed with a larger count: exactly one more trial, the first two untouched.
    assert tune(["rbf", *SMOKE, "--trials", "3", "--root", str(tmp_path)]) == 0
    again = _complete(space, tmp_path)
    assert [t.number for t in again] == [0, 1, 2]
    assert [t.params for t in again[:2]] == [t.params for t in first]
    assert tune(["rbf", *SMOKE, "--trials", "3", "--root", str(tmp_path)]) == 0
    assert len(_study(space, tmp_path).trials) == 3

    trials = pd.read_csv(folder / "trials.csv")
    assert list(trials["trial"]) == [0, 1, 2] and list(trials["role"]) == ["defaults", "random", "random"]
    for column in ("objective", "algorithm.lambda_", "reward_loss.seed_1002", "learning_span.seed_1000",
                   "first_target_reward_step.seed_1001", "first_threshold_step.seed_1000", "mean_reward@200"):
        assert column in trials.columns

    settings = tracking.TrackingSettings(f"sqlite:///{tmp_path / 'mlflow.db'}")
    runs = tracking.find_runs(settings, mlflow_log.EXPERIMENT)
    parents = [r for r in runs if "mlflow.parentRunId" not in r.data.tags]
    children = [r for r in runs if r.data.tags.get("mlflow.parentRunId") == parents[0].info.run_id]
    assert len(parents) == 1 and sorted(int(r.data.tags["tuning_trial"]) for r in children) == [0, 1, 2]
    history = settings.client().get_metric_history(children[0].info.run_id, "mean_reward")
    assert sorted(m.step for m in history) == [100, 200]  # the curve, step = learning step

    assert table1(["--root", str(tmp_path), "--scale", "smoke"]) == 0
    text = (tmp_path / "reports" / "smoke" / "table1.md").read_text()
    assert "## rbf" in text and "3 trials finished" in text and "tuning seeds 1000, 1001, 1002" in text
    assert "`algorithm.epsilon` | 0.01 - 0.3 (log) | 0.1 |" in text
    assert "Not tuned yet" in text  # fsr and dqn
    assert (tmp_path / "reports" / "smoke" / "table1_rbf.png").stat().st_size > 10_000


@pytest.mark.filterwarnings("ignore:Heartbeat of storage is supposed to be used with Study.optimize")
def test_a_trial_whose_worker_died_is_redone_with_its_values(space, tmp_path, monkeypatch):
    monkeypatch.setattr(study_module, "GRACE_S", 1)
    plan = study_module.prepare(StudyPlan(space, study_folder(tmp_path, space), trials=1))
    study = load_study(plan)
    study.ask()  # the queued defaults: pretend a worker takes them
    dead = study.ask({p.key: p.distribution() for p in space.params})
    study._storage.record_heartbeat(dead._trial_id)  # its last heartbeat; then the worker dies
    time.sleep(2)
    study.tell(0, state=optuna.trial.TrialState.FAIL)  # Ctrl-C: failed without a retry
    assert tune(["rbf", *SMOKE, "--trials", "2", "--root", str(tmp_path), "--tracking", "none"]) == 0
    done = _complete(space, tmp_path)
    assert len(done) == 2
    assert {t.user_attrs["role"] for t in done} == {"defaults", "random"}
    assert dead.params in [t.params for t in done]


def test_first_step_at_threshold_and_the_learning_span_in_a_trial_record():
    steps = [100, 200, 300, 400]
    assert first_step_at_threshold(steps, [0.0, 8.0, 7.0, 9.0], 8.0) == 200  # reached, not stable
    assert first_step_at_threshold(steps, [0.0, 7.9, 7.0, 1.0], 8.0) is None

    def result(rewards, discovery):
        return RunResult("linear_q", "rbf", "none", 0, 0, 400, steps, rewards, [r / 10 for r in rewards],
                         sum(10 - r for r in rewards), None, None, 0, 1.0, 1.0,
                         first_target_reward_step=discovery)

    record = trial_record([1000, 1001], [result([0, 8, 9, 10], 150), result([0, 0, 0, 4], None)], 8.0)
    assert record["mean_curve"] == [0.0, 4.0, 4.5, 7.0]
    assert record["reward_loss"] == [13.0, 36.0]
    assert record["first_threshold_step"] == [200, None] and record["learning_span"] == [50, None]


def test_trial_k_draws_the_same_values_in_any_study(space):
    distributions = {p.key: p.distribution() for p in space.params}

    def draws(skip: int) -> dict:
        study = optuna.create_study(sampler=TrialSeededRandomSampler(space.sampler_seed))
        for _ in range(skip):
            study.ask()  # other trials (another worker's, or before a resumption)
        study.ask(distributions)  # the trial before: consumes draws in a single-stream sampler
        return study.ask(distributions).params

    assert draws(0) != draws(1)  # the trial number matters ...
    study = optuna.create_study(sampler=TrialSeededRandomSampler(space.sampler_seed))
    study.ask()
    study.ask()  # ... and nothing else: trial 2 gets the same values with no draw before it
    assert study.ask(distributions).params == draws(1)


@pytest.mark.parametrize("change, key", [
    (("algorithm.epsilon:", "algorithm.epsilonn:"), "params.algorithm.epsilonn"),
    (("seeds: [1000, 1001, 1002]", "seeds: [1000, 3]"), "seeds"),
    (("    low: 0.01\n", "    low: 0\n"), "params.algorithm.epsilon.low"),
    (("    low: 100.0\n    high: 1000000.0", "    low: 100.0\n    high: 10.0"), "params.algorithm.boyan_n0"),
    (("choices: [true, false]", "choices: [true, 1]"), "params.representation.normalize.choices"),
    (("scale: paper", "scale: huge"), "scale"),
    (("sampler: {name: random,", "sampler: {name: grid,"), "sampler.name"),
])
def test_a_bad_search_space_is_refused_in_one_line_naming_the_key(tmp_path, change, key):
    text = (SEARCH_SPACE_DIR / "linear_q_rbf.yaml").read_text()
    assert change[0] in text
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(change[0], change[1], 1))
    with pytest.raises(SearchSpaceError) as error:
        load_search_space(path)
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"bad.yaml: {key}:")


def test_every_search_space_loads_and_tunes_without_transfer_on_tuning_seeds():
    for path in sorted(SEARCH_SPACE_DIR.glob("*.yaml")):
        space = load_search_space(path)
        assert all(seed >= 20 for seed in space.seeds) and len(space.seeds) >= 3
        assert space.scale == "paper" and "strategy=none" in space.base
        for p in space.params:
            assert p.why


def test_every_refinement_loads_on_seeds_its_search_did_not_choose_on():
    from mediated_transfer.tuning import refine

    for path in sorted((SEARCH_SPACE_DIR / "refine").glob("*.yaml")):
        refinement = refine.load_refinement(path.stem)
        names = [c.name for c in refinement.candidates]
        assert "defaults" in names and len(names) >= 3, path.name
        # The DQN's and PPO's refinements were declared after their searches: fresh seeds (the
        # winner's curse); the linear learners' older ones share the search's seeds.
        if path.stem in {"dqn", "ppo"}:
            assert not set(refinement.seeds) & set(refinement.space.seeds), path.name
        assert len(refinement.seeds) >= 10


def test_a_study_refuses_to_continue_with_another_search_space(space, tmp_path):
    folder = study_folder(tmp_path, space)
    study_module.prepare(StudyPlan(space, folder, trials=1))
    other = dataclasses.replace(space, seeds=(1000, 1001))
    with pytest.raises(study_module.StudyMismatchError, match=r"another search space \(seeds differ"):
        study_module.prepare(StudyPlan(other, folder, trials=1))


def _refine_folder(tmp_path, learner: str, text: str):
    """A search-space folder holding ``learner``'s search space and ``text`` as its refinement file."""
    import shutil

    folder = tmp_path / "spaces"
    (folder / "refine").mkdir(parents=True, exist_ok=True)
    shutil.copy(find_search_space(learner).path, folder)
    (folder / "refine" / f"{learner}.yaml").write_text(text)
    return folder


def test_refinement_runs_each_candidate_on_each_seed_once_and_resumes(tmp_path, capsys):
    from mediated_transfer.tuning import refine

    folder = _refine_folder(tmp_path, "fsr", "learner: fsr\nseeds: [1000, 1001]\ncandidates:\n"
                            "  defaults: {from: provisional defaults, values: {}}\n"
                            "  greedy: {from: a test, values: {algorithm.epsilon: 0.01}}\n")
    refinement = refine.load_refinement("fsr", folder, scale="smoke")
    assert [c.name for c in refinement.candidates] == ["defaults", "greedy"]
    assert refinement.candidates[1].values["algorithm.epsilon"] == 0.01
    assert refinement.candidates[1].values["algorithm.lambda_"] == refinement.space.defaults["algorithm.lambda_"]
    # Seed by seed, so a refinement stopped midway has compared every candidate on the same seeds.
    assert [(c.name, s) for c, s in refinement.runs()] == [
        ("defaults", 1000), ("greedy", 1000), ("defaults", 1001), ("greedy", 1001)]

    rows = refine.refine(refinement, tmp_path / "out")
    assert "[refine fsr 4/4, ~0m00s left]" in capsys.readouterr().out
    assert sorted(zip(rows["candidate"], rows["seed"])) == [
        ("defaults", 1000), ("defaults", 1001), ("greedy", 1000), ("greedy", 1001)]
    again = refine.refine(refinement, tmp_path / "out")  # nothing left to run
    assert len(again) == 4 and "0 to run" in capsys.readouterr().out
    text = refine.section(refinement, again)
    assert "| defaults | provisional defaults | 2 |" in text and "| greedy | a test | 2 |" in text
    assert "Not finished" not in text
    # Stopped after its first run: the table says so, and a candidate without runs shows '-'.
    partial = refine.section(refinement, again.iloc[:1])
    assert "**Not finished: 1 of 4 runs so far**" in partial
    assert "| greedy | a test | 0 | - | - | 0/0 |" in partial and "nan" not in partial

    (folder / "refine" / "fsr.yaml").write_text("learner: fsr\nseeds: [3]\ncandidates: {}\n")
    with pytest.raises(SearchSpaceError, match="table seeds"):
        refine.load_refinement("fsr", folder, scale="smoke")


def _refine_rows(losses: dict[str, list[float]], first_seed: int = 1003):
    import pandas as pd

    from mediated_transfer.tuning.refine import COLUMNS

    return pd.DataFrame([{"candidate": name, "seed": first_seed + k, "reward_loss": loss}
                         for name, per_seed in losses.items() for k, loss in enumerate(per_seed)],
                        columns=COLUMNS)


def _dqn_refinement(tmp_path, choice: str | None):
    from mediated_transfer.tuning import refine

    folder = _refine_folder(
        tmp_path, "dqn", "learner: dqn\nseeds: [1003, 1004, 1005]\n" + (f"choice: {choice}\n" if choice else "")
        + "candidates:\n"
        "  costly: {from: a test, values: {algorithm.train_frequency: 1, algorithm.batch_size: 128}}\n"
        "  cheap: {from: a test, values: {algorithm.train_frequency: 4, algorithm.batch_size: 32}}\n"
        "  middle: {from: a test, values: {algorithm.train_frequency: 2, algorithm.batch_size: 32}}\n")
    return refine.load_refinement("dqn", folder, scale="smoke")


def test_refinement_choice_lowest_mean_or_the_cheapest_within_one_sem(tmp_path):
    from mediated_transfer.tuning import refine

    lowest = _dqn_refinement(tmp_path, None)
    rule = _dqn_refinement(tmp_path, "cheapest_within_one_sem")
    costs = {c.name: refine.update_cost(c.values) for c in rule.candidates}
    assert costs["costly"] == pytest.approx(16 * costs["cheap"]) and costs["middle"] == 2 * costs["cheap"]
    # costly: mean 50, SEM 11.5 -> the band reaches 61.5; middle (58) is in it, cheap (63) is not.
    rows = _refine_rows({"costly": [30, 50, 70], "middle": [58, 58, 58], "cheap": [63, 63, 63]})
    assert refine.choose(lowest, rows)[0] == "costly"
    name, why = refine.choose(rule, rows)
    assert name == "middle" and "within one SEM of the lowest mean (`costly`, 50.0 ± 11.5)" in why
    assert "at 0.12 of its update cost" in why
    # Nothing cheaper within the band: the lowest mean stays.
    far = _refine_rows({"costly": [30, 50, 70], "middle": [75] * 3, "cheap": [62, 63, 64]})
    assert refine.choose(rule, far)[0] == "costly"
    text = refine.section(rule, rows)
    assert "| costly | a test | 3 | 50.0 ± 11.5 |" in text and "| 16x |" in text
    assert "Chosen by the refinement's rule (the one-standard-error rule: the cheapest" in text  # all 9 runs done
    assert "Leading so far" not in text
    assert "**Leading so far**" in refine.section(rule, rows.iloc[:4])
    assert refine.choose(rule, rows.iloc[:0]) is None


def test_refinement_time_left_weighs_each_run_by_its_update_cost(tmp_path):
    import time

    from mediated_transfer.tuning import refine

    rule = _dqn_refinement(tmp_path, None)
    by_name = {c.name: c for c in rule.candidates}
    per_work = 60.0 / refine.update_cost(by_name["cheap"].values)  # a cheap run: a minute
    # A costly run (16x) under way for 5 minutes, a cheap and a middle one (2x) waiting.
    running = [(by_name["costly"], time.monotonic() - 300)]
    left = refine._compute_left(rule, per_work, running, [by_name["cheap"], by_name["middle"]])
    assert left == pytest.approx(16 * 60 - 300 + 60 + 2 * 60, abs=2)


def test_refinement_choice_is_checked_before_any_run(tmp_path):
    from mediated_transfer.tuning import refine

    with pytest.raises(SearchSpaceError, match=r"choice must be one of lowest_mean, cheapest_within_one_sem, got 'cheapest'"):
        _dqn_refinement(tmp_path, "cheapest")
    folder = _refine_folder(
        tmp_path, "fsr", "learner: fsr\nseeds: [1000]\nchoice: cheapest_within_one_sem\ncandidates: {a: {values: {}}}\n")
    with pytest.raises(SearchSpaceError, match="needs a run cost, known for the dqn learner only"):
        refine.load_refinement("fsr", folder, scale="smoke")


RACE = {"defaults": [10.0, 12.0, 11.0, 13.0], "greedy": [100.0, 110.0, 105.0, 108.0]}


def _raced_run(space, candidate, seed):
    """A stand-in for refine.run_one (module level: the worker process unpickles it)."""
    return {"candidate": candidate.name, "seed": seed, "reward_loss": RACE[candidate.name][seed - 1000]}


def _failing_run(space, candidate, seed):
    if candidate.name == "greedy":
        raise RuntimeError("the launcher went away")
    return _raced_run(space, candidate, seed)


def test_a_failed_refinement_run_keeps_the_finished_ones_and_raises(tmp_path, monkeypatch):
    from mediated_transfer.tuning import refine

    folder = _refine_folder(tmp_path, "fsr", "learner: fsr\nseeds: [1000, 1001]\ncandidates:\n"
                            "  defaults: {from: provisional defaults, values: {}}\n  greedy: {from: a test, values: {}}\n")
    monkeypatch.setattr(refine, "run_one", _failing_run)
    with pytest.raises(RuntimeError, match="the launcher went away"):
        refine.refine(refine.load_refinement("fsr", folder, scale="smoke"), tmp_path / "out", workers=1)
    # Nothing started after the failure; what finished before it is in the file.
    saved = (tmp_path / "out" / refine.REFINE_FILE).read_text().splitlines()
    assert len(saved) == 2 and saved[1].startswith("defaults,1000,10.0")


def test_racing_drops_a_clearly_worse_candidate_and_runs_it_no_more(tmp_path, capsys, monkeypatch):
    from mediated_transfer.tuning import refine

    folder = _refine_folder(
        tmp_path, "fsr", "learner: fsr\nseeds: [1000, 1001, 1002, 1003]\nracing: {min_seeds: 2, p_value: 0.05}\n"
        "candidates:\n  defaults: {from: provisional defaults, values: {}}\n"
        "  greedy: {from: a test, values: {algorithm.epsilon: 0.01}}\n")
    refinement = refine.load_refinement("fsr", folder, scale="smoke")
    # After seed 1000 alone nothing is decided; after 1001: greedy is worse by 94 (leader's SEM 1),
    # paired t = 23.5 on 1 degree of freedom, one-sided p = 0.014 < 0.05.
    rows = _refine_rows({name: losses[:2] for name, losses in RACE.items()}, first_seed=1000)
    assert refine.dropped(refinement, rows.iloc[[0, 2]]) == {}
    out = refine.dropped(refinement, rows)
    assert list(out) == ["greedy"] and out["greedy"].seed == 1001
    assert out["greedy"].why.startswith("dropped after seed 1001 (2 seeds): L_R 105.0 against `defaults`'s 11.0")
    assert "p = 0.014" in out["greedy"].why
    # A seed not every remaining candidate has run decides nothing.
    assert refine.dropped(refinement, rows.iloc[[0, 1, 2]]) == {}

    monkeypatch.setattr(refine, "run_one", _raced_run)
    done = refine.refine(refinement, tmp_path / "out", workers=1)
    printed = capsys.readouterr().out
    assert sorted(zip(done["candidate"], done["seed"])) == [
        ("defaults", 1000), ("defaults", 1001), ("defaults", 1002), ("defaults", 1003),
        ("greedy", 1000), ("greedy", 1001)]
    assert "[refine fsr] greedy dropped after seed 1001" in printed and "[refine fsr 6/6," in printed
    text = refine.section(refinement, done)
    assert "Not finished" not in text and "- `greedy`: dropped after seed 1001" in text
    assert "| greedy | a test | 2 (dropped) | 105.0 ± 5.0 |" in text
    assert "Chosen by the refinement's rule (the lowest mean L_R): `defaults`" in text
    # A run of greedy under way at the drop and finished after it changes neither the table
    # nor the choice, even where it, or the leader's later seeds, would make greedy the best.
    late = _refine_rows({"defaults": [10, 12, 200, 200], "greedy": [100, 110, 0]}, first_seed=1000)
    assert "| greedy | a test | 2 (dropped) | 105.0 ± 5.0 |" in refine.section(refinement, late)
    assert refine.choose(refinement, late)[0] == "defaults"
    # Resumed: the same decision from the file, nothing left to run.
    refine.refine(refinement, tmp_path / "out", workers=1)
    assert "0 to run, 1 worker(s); dropped by racing: greedy" in capsys.readouterr().out

    (folder / "refine" / "fsr.yaml").write_text(
        "learner: fsr\nseeds: [1000, 1001]\nracing: {min_seeds: 3, p_value: 0.05}\ncandidates: {a: {values: {}}}\n")
    with pytest.raises(SearchSpaceError, match=r"racing.min_seeds must be in 2..2 \(the seeds\)"):
        refine.load_refinement("fsr", folder, scale="smoke")


def test_a_diverged_run_scores_zero_reward_for_the_rest_of_its_budget():
    import re

    from mediated_transfer.tuning.objective import run_seed

    result, _ = run_seed(["algorithm=linear_q", "representation=fsr", "strategy=regular", "n_source=50",
                          "algorithm.alpha0=1e30", "scale=smoke", "scale.budget=20000", "scale.eval_points=4",
                          "tracking=none", "seed=1000"])
    stopped = int(re.search(r"diverged by step (\d+)", result.failure).group(1))
    assert stopped < 20000 and result.steps == [5000, 10000, 15000, 20000]
    assert all(r == 0.0 for s, r in zip(result.steps, result.mean_reward) if s > stopped)
    assert result.reward_loss == pytest.approx(sum(10.0 - r for r in result.mean_reward))


def test_a_trial_stops_when_the_tuning_process_that_started_it_is_gone(monkeypatch):
    from mediated_transfer.tuning import objective

    from .test_orphan import orphaned_pool_worker

    orphaned_pool_worker(monkeypatch)  # a worker of the tuning's pool, orphaned after its trial started
    with pytest.raises(KeyboardInterrupt, match="launching process is gone"):
        objective.run_seed(["scale=smoke", "tracking=none", "seed=1000"])


def test_a_trial_stops_once_its_reward_loss_so_far_exceeds_the_best_and_not_before(space):
    """The lower bound is exact: (L_R of the seeds done + L_R of the running seed's points so
    far) / seeds; a ceiling just above the first seed's share stops the trial at the second
    seed's first point with any loss, and a ceiling the trial stays below changes nothing."""
    from mediated_transfer.tuning.objective import StoppedEarly, evaluate

    values = dict(space.defaults)
    full, record = evaluate(space, values)
    again, same = evaluate(space, values, ceiling=lambda: full + 1e-9)
    assert again == full and same["curves"] == record["curves"]

    first = record["reward_loss"][0]
    ceiling = first / 3 + 1e-9
    with pytest.raises(StoppedEarly) as stop:
        evaluate(space, values, ceiling=lambda: ceiling)
    second = record["curves"][1]
    point = next(i for i, r in enumerate(second) if r < 10.0)  # the first point that adds loss
    assert (stop.value.seed, stop.value.step) == (1001, record["steps"][point])
    assert stop.value.lower_bound == pytest.approx((first + sum(10.0 - r for r in second[:point + 1])) / 3)
    assert stop.value.record["seeds"] == [1000] and stop.value.record["reward_loss"] == [first]


@pytest.mark.slow
def test_a_stopped_trial_counts_toward_the_trials_and_shows_as_a_lower_bound(space, tmp_path, monkeypatch, capsys):
    # Every random trial meets a best of 0: it stops at its first evaluation point with loss.
    monkeypatch.setattr(study_module, "best_objective", lambda study: 0.0)
    fresh_store(tmp_path)
    assert tune(["rbf", *SMOKE, "--trials", "2", "--root", str(tmp_path)]) == 0
    trials = _study(space, tmp_path).get_trials()
    assert [t.state.name for t in trials] == ["COMPLETE", "PRUNED"]  # the defaults are never stopped
    stopped = trials[1]
    assert stopped.value == pytest.approx(stopped.user_attrs["stopped_early"]["lower_bound"]) and stopped.value > 0
    assert stopped.user_attrs["stopped_early"]["seed"] == 1000 and "reward_loss" not in stopped.user_attrs
    assert re.search(r"trial 1 \(random\): stopped early at seed 1000, step \d+: L_R >= [\d.]+; best",
                     capsys.readouterr().out)

    csv = pd.read_csv(tmp_path / "tuning" / "rbf" / "smoke" / "trials.csv")
    assert list(csv["stopped_early"]) == [False, True] and pd.isna(csv.loc[1, "reward_loss.seed_1000"])
    settings = tracking.TrackingSettings(f"sqlite:///{tmp_path / 'mlflow.db'}")
    child = next(r for r in tracking.find_runs(settings, mlflow_log.EXPERIMENT)
                 if r.data.tags.get("tuning_trial") == "1")
    assert "reward_loss_lower_bound" in child.data.metrics and "stopped_early" in child.data.tags

    assert table1(["--root", str(tmp_path), "--scale", "smoke"]) == 0
    text = (tmp_path / "reports" / "smoke" / "table1.md").read_text()
    assert "2 trials finished" in text and "1 of them were stopped early" in text
    assert "rank 1 of 1 run to the end" in text


def test_table1_s_figure_places_a_choice_as_the_csv_spells_it():
    """PPO's ent_coef choice 0.0 comes back from trials.csv as 0 (and n_steps as numpy ints):
    the figure places each on its choice, not a KeyError."""
    import numpy as np

    from mediated_transfer.tuning.table1_figure import _choice_key

    assert _choice_key(0) == _choice_key(0.0) == _choice_key(np.float64(0.0))
    assert _choice_key(np.int64(2048)) == _choice_key(2048) != _choice_key(1024)
    assert _choice_key("True") == _choice_key(True) != _choice_key(1.0)
