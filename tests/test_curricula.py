"""The automatic curricula of src/auto_curricula (plugins through the strategy API), each on
scripted outcomes against its paper's description, and the record of what a run's episodes
started from."""

import math
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf
from scipy import stats

import auto_curricula
from auto_curricula.domain_randomisation import DomainRandomisation
from auto_curricula.learnability import Learnability
from auto_curricula.plr import PrioritizedLevelReplay
from auto_curricula.reverse import ReverseCurriculum
from mediated_transfer.env import Task
from mediated_transfer.env.task_space import TaskSpace
from mediated_transfer.transfer import EpisodeOutcome, StrategyContext
from mediated_transfer.curricula.measures import verdict, word
from mediated_transfer.results import RunResult
from mediated_transfer.run import RunSpec, execute_run
from mediated_transfer.transfer.choices import EpisodeChoices

from .optional import importorskip

CURRICULA_CONF = Path(auto_curricula.__file__).parent / "conf"

SPACE = TaskSpace()
REVERSE = dict(r_min=0.1, r_max=0.9, new_starts=10, old_starts=5, rollouts=5, walk_steps=10, step_std=0.5,
               pool=1000)  # conf/strategy/reverse.yaml


def context(seed=0, n_tasks=0):
    tasks = [Task((float(i) + 3.0, 0.0), (0.0, -3.0), 0.0) for i in range(n_tasks)]
    return StrategyContext.of_tasks(tasks, np.random.default_rng(seed))


def outcome(task, solved, td_error=None):
    return EpisodeOutcome(task, bool(solved), 10.0 if solved else 0.0, 1, 1, td_error)


def distance(task):
    return None if task is None else task.target_distance


# --- domain randomisation --------------------------------------------------------------------


def test_domain_randomisation_draws_the_target_distance_uniformly_and_ignores_outcomes():
    low, high = SPACE.distances
    target_from = SPACE.target_distances[0]
    runs = []
    for solved in (True, False):  # no feedback: the outcomes must change nothing
        strategy = DomainRandomisation(context(seed=3))
        chosen = []
        for _ in range(3000):
            task = strategy.next_task()
            chosen.append(distance(task))
            strategy.report(outcome(task, solved))
        assert not strategy.done
        runs.append(chosen)
    assert runs[0] == runs[1]
    near = np.array([d for d in runs[0] if d is not None])
    # A target task exactly when the drawn distance falls in the target annulus.
    share = 1 - len(near) / len(runs[0])
    assert share == pytest.approx((high - target_from) / (high - low), abs=0.03)
    assert near.max() < target_from and near.min() >= low
    assert stats.kstest(near, stats.uniform(loc=low, scale=target_from - low).cdf).pvalue > 0.01


# --- reverse curriculum (Florensa et al. 2017) ----------------------------------------------


def play_iteration(strategy, solves):
    """One iteration: every start rolled out ``rollouts`` times, solved when ``solves(d)``."""
    tried = []
    for _ in range((strategy.new_starts + strategy.old_starts) * strategy.rollouts):
        task = strategy.next_task()
        tried.append(round(task.target_distance, 9))
        strategy.report(outcome(task, solves(task.target_distance)))
    return tried


def play_by_start(strategy, solves):
    """One iteration, solved when ``solves(index, attempt)``: ``index`` the start's place in
    ``strategy._starts`` (new starts first, then the replayed old ones), ``attempt`` 0, 1, ...
    of its rollouts. Returns the iteration's starts."""
    starts = list(strategy._starts)
    attempts = {}
    for _ in range(len(starts) * strategy.rollouts):
        task = strategy.next_task()
        index = strategy._pending
        attempt = attempts[index] = attempts.get(index, -1) + 1
        strategy.report(outcome(task, solves(index, attempt)))
    return starts


class LineSpace:
    """The task space's distances, and a task at a distance made without rejection sampling (on
    the x axis): the strategy's logic at a fraction of the cost of TaskSpace.sample's draws."""

    distances = SPACE.distances
    target_distances = SPACE.target_distances

    def sample(self, rng, distance):
        return Task((float(distance), 0.0), (0.0, -3.0), 0.0)


def walk_reach(strategy):
    """Four standard deviations of one SampleNearby walk's end from its seed."""
    return 4 * strategy.step_std * np.sqrt(strategy.walk_steps)


def test_reverse_starts_at_the_goal_and_tries_each_start_rollouts_times_per_iteration():
    strategy = ReverseCurriculum(context(seed=1), **REVERSE)
    starts = list(strategy._starts)
    assert len(starts) == 15  # N_new + N_old = 10 + 5
    low = SPACE.distances[0]
    assert strategy.seeds == [low] and strategy.old == [low] and strategy.good == []
    assert starts[10:] == [low] * 5  # replayed from starts_old: only the goal so far
    # New starts: states of random walks from the goal, reflected at the task space's near end.
    assert all(low < d <= low + walk_reach(strategy) for d in starts[:10])
    tried = play_iteration(strategy, lambda d: True)
    counts = {d: tried.count(d) for d in set(tried)}
    # Each start's episodes (a start may repeat, e.g. a replayed goal): 5 per start.
    assert sum(counts.values()) == 75 and all(c % 5 == 0 for c in counts.values())
    assert counts[round(low, 9)] == 25  # the goal, replayed 5 times
    assert strategy.iterations == 1


def test_reverse_sample_nearby_draws_from_the_states_of_walks_from_the_seeds():
    strategy = ReverseCurriculum(context(seed=11), **REVERSE)
    low, high = SPACE.distances
    seeds = [4.0, 9.0]
    drawn = np.array(strategy.sample_nearby(seeds, 4000))
    assert drawn.min() >= low and drawn.max() <= high
    # Every state lies near a seed, and both seeds grow states (the walks start at either).
    near = np.min(np.abs(drawn[:, None] - np.array(seeds)[None, :]), axis=1)
    assert near.max() <= walk_reach(strategy)
    assert 0.3 < np.mean(drawn < 6.5) < 0.7
    # The states of a walk's every step, not only its end: many lie within one step of a seed.
    assert np.mean(near <= strategy.step_std) > 0.15
    # A walk reflects at the near end: none piles up at the goal.
    at_goal = np.array(ReverseCurriculum(context(seed=12), **REVERSE).sample_nearby([low], 4000))
    assert at_goal.min() > low and np.mean(at_goal < low + 0.05) < 0.05


def test_reverse_keeps_the_starts_whose_success_lies_in_the_band():
    strategy = ReverseCurriculum(context(seed=2), **REVERSE)
    starts = np.array(strategy._starts)
    edge = float(np.median(starts[:10]))
    # Starts nearer than `edge` (the goal replayed among them) are always solved (too easy),
    # farther ones 2 of 5 times (in band).
    play_by_start(strategy, lambda k, attempt: starts[k] < edge or attempt < 2)
    in_band = sorted(starts[starts >= edge].tolist())  # new starts only (the goal is nearer)
    assert len(in_band) >= 5  # a start may be drawn twice from SampleNearby's collection
    assert sorted(strategy.good) == pytest.approx(in_band)
    assert sorted(strategy.seeds) == pytest.approx(in_band)  # all of them new starts
    assert strategy.old[0] == SPACE.distances[0] and strategy.old[1:] == strategy.good  # join starts_old
    # The next iteration's new starts grow out of the good ones; its replayed ones come from starts_old.
    assert all(min(in_band) - walk_reach(strategy) <= d <= max(in_band) + walk_reach(strategy)
               for d in strategy._starts[:10])
    assert set(strategy._starts[10:]) <= set(strategy.old)


def test_reverse_never_seeds_from_a_replayed_old_start():
    low = SPACE.distances[0]
    # First iteration: only the replayed goal is in the band, the new starts are mastered. The
    # goal is a good start (it joins starts_old) but the next iteration grows from the mastered
    # new starts, not from the goal.
    strategy = ReverseCurriculum(context(seed=13), **REVERSE)
    first = play_by_start(strategy, lambda k, attempt: k < 10 or attempt < 2)
    assert strategy.good == [low] * 5 and strategy.old == [low] * 6
    assert sorted(strategy.seeds) == sorted(first[:10]) and low not in strategy.seeds

    # Second iteration: the new starts are in the band, the replayed ones mastered: the seeds are
    # exactly the new starts. Third: the new starts are hopeless, only the replayed ones (good
    # starts of the second iteration) are in the band: the seeds stay the second iteration's.
    second = play_by_start(strategy, lambda k, attempt: k >= 10 or attempt < 2)
    assert sorted(strategy.seeds) == sorted(second[:10])
    assert sorted(strategy.good) == sorted(second[:10])
    seeds = list(strategy.seeds)
    third = play_by_start(strategy, lambda k, attempt: k >= 10 and attempt < 2)
    replayed = third[10:]
    assert set(replayed) <= set(second[:10]) | {low}
    assert sorted(strategy.good) == sorted(replayed)  # good starts: the replayed ones too
    assert strategy.seeds == seeds  # ... but not seeds

    # Where some new starts are in the band beside replayed ones, only those new starts seed.
    fourth = play_by_start(strategy, lambda k, attempt: (k >= 10 or k % 2 == 0) and attempt < 2)
    assert sorted(strategy.seeds) == sorted(fourth[0:10:2])
    assert sorted(strategy.good) == sorted(fourth[0:10:2] + fourth[10:])


def test_reverse_reaches_the_target_annulus_in_few_iterations_for_a_learner_that_solves_everything():
    """Bounds issue 42's defect: seeding from the replayed old starts snapped a third of the seeds
    back to the goal every iteration, and a learner that solves every task needed a median of
    hundreds of iterations (seeds 0..19 of that version: median > 70, four beyond 200). Now
    (100 seeds, with TaskSpace's tasks): median 18, at most 66."""
    target_from = SPACE.target_distances[0]
    iterations = []
    for seed in range(20):
        strategy = ReverseCurriculum(context(seed=seed), **REVERSE)
        strategy.space = LineSpace()
        frontier = []
        while not strategy.done and strategy.iterations < 80:
            play_iteration(strategy, lambda d: True)
            if not strategy.done:
                assert strategy.good == []  # every start mastered: none in the band ...
                frontier.append(max(strategy.seeds))  # ... the mastered new starts seed
        assert strategy.done, f"seed {seed}: no start in the target annulus after 80 iterations"
        assert max(strategy._starts) >= target_from  # ended by a start in the annulus with R >= R_min
        assert not frontier or frontier[-1] > frontier[0]
        iterations.append(strategy.iterations)
    assert np.median(iterations) <= 30, iterations


def test_reverse_with_hopeless_starts_stays_at_the_previous_seeds():
    low = SPACE.distances[0]
    strategy = ReverseCurriculum(context(seed=5), **REVERSE)
    for _ in range(2):
        play_iteration(strategy, lambda d: False)
        assert strategy.seeds == [low] and strategy.good == [] and strategy.old == [low]
        assert not strategy.done
        assert strategy._starts[10:] == [low] * 5
        assert all(low < d <= low + walk_reach(strategy) for d in strategy._starts[:10])
    assert strategy.iterations == 2


@pytest.mark.parametrize("key, value, message", [
    ("r_min", 0.95, "strategy.r_min and strategy.r_max"), ("r_max", 1.5, "strategy.r_min and strategy.r_max"),
    ("new_starts", 0, "strategy.new_starts"), ("rollouts", 2.0, "strategy.rollouts"),
    ("walk_steps", True, "strategy.walk_steps"), ("pool", 0, "strategy.pool"),
    ("old_starts", -1, "strategy.old_starts"), ("step_std", 0.0, "strategy.step_std")])
def test_reverse_refuses_parameters_out_of_range(key, value, message):
    with pytest.raises(ValueError, match=message):
        ReverseCurriculum(context(), **{**REVERSE, key: value})
    if key in ("r_min", "r_max"):
        with pytest.raises(ValueError, match=message):
            ReverseCurriculum(context(), **{**REVERSE, "r_min": 0.9, "r_max": 0.1})


# --- Prioritized Level Replay (Jiang et al. 2021) --------------------------------------------


def test_plr_rank_prioritisation_and_staleness_follow_the_paper():
    strategy = PrioritizedLevelReplay(context(n_tasks=2), temperature=0.1, staleness=0.0)
    strategy.seen[:] = True
    strategy.scores[:] = [3.0, 1.0, 2.0]  # ranks 1, 3, 2
    h = np.array([1.0, 1 / 3, 1 / 2]) ** 10
    np.testing.assert_allclose(strategy.replay_distribution(), h / h.sum())
    strategy.staleness = 1.0
    strategy.episodes = 10
    strategy.last_sampled[:] = [10, 4, 8]  # 0, 6 and 2 episodes ago
    np.testing.assert_allclose(strategy.replay_distribution(), [0, 0.75, 0.25])


def test_plr_tries_unseen_levels_first_replays_the_highest_td_error_and_hands_out_target_tasks_as_none():
    strategy = PrioritizedLevelReplay(context(seed=6, n_tasks=4), temperature=0.1, staleness=0.1)
    error = {3.0: 5.0, 4.0: 0.1, 5.0: 0.1, 6.0: 0.1, None: 0.2}  # by target x (None: target task)
    first = []
    counts = {}
    for episode in range(600):
        task = strategy.next_task()
        key = None if task is None else float(task.target_position[0])
        if episode < 5:
            first.append(key)
        counts[key] = counts.get(key, 0) + 1
        strategy.report(outcome(task, False, td_error=error[key]))
    assert strategy.seen.all()
    assert counts[3.0] > 0.8 * 600  # rank 1 at beta = 0.1 takes almost all replays
    assert None in counts  # the target task is a level
    assert not strategy.done


def test_plr_needs_td_errors():
    strategy = PrioritizedLevelReplay(context(n_tasks=1), temperature=0.1, staleness=0.1)
    task = strategy.next_task()
    with pytest.raises(RuntimeError, match="TD error"):
        strategy.report(outcome(task, True))


# --- learnability (SFL) ----------------------------------------------------------------------


def test_learnability_buffers_the_levels_nearest_p_one_half_and_draws_from_it_at_rate_rho():
    strategy = Learnability(context(seed=7, n_tasks=5), buffer_size=2, buffer_share=0.5, window=10)
    success = {3.0: 1.0, 4.0: 0.5, 5.0: 0.2, 6.0: 0.0, 7.0: 0.5, None: 0.0}
    for level, p in success.items():
        index = strategy.levels.target if level is None else int(level) - 3
        for solved in [True] * int(10 * p) + [False] * (10 - int(10 * p)):
            _report(strategy, index, solved)
    np.testing.assert_allclose(strategy.learnability(), [0, 0.25, 0.16, 0, 0.25, 0])
    assert strategy.buffer().tolist() == [1, 4]
    counts = np.zeros(6)
    for _ in range(6000):
        task = strategy.next_task()
        counts[strategy.levels.target if task is None else int(task.target_position[0]) - 3] += 1
        strategy.levels._pending = None  # outcomes would move p: keep the buffer fixed here
    expected = np.full(6, 0.5 / 6)
    expected[[1, 4]] += 0.25
    np.testing.assert_allclose(counts / 6000, expected, atol=0.02)


def _report(strategy: Learnability, index: int, solved: bool) -> None:
    """An episode of level ``index`` reported as if the strategy had handed it out."""
    strategy.levels._pending = index
    strategy.report(outcome(None if index == strategy.levels.target else strategy.levels.tasks[index], solved))


def test_learnability_estimates_p_from_the_last_window_episodes():
    strategy = Learnability(context(seed=8, n_tasks=1), buffer_size=1, buffer_share=1.0, window=4)
    for solved in (True, True, True, True, False, False):
        _report(strategy, 0, solved)
    assert strategy.learnability()[0] == pytest.approx(0.25)  # last four: 1, 1, 0, 0
    assert strategy.solved_count == 1


def test_learnability_is_exactly_the_mean_of_each_levels_window():
    """The running sums give bit for bit what the mean over each window gives (the committed
    study runs were computed with the mean), over thousands of outcomes at random levels."""
    strategy = Learnability(context(seed=9, n_tasks=20), buffer_size=5, buffer_share=0.5, window=10)
    rng = np.random.default_rng(0)
    for _ in range(5000):
        _report(strategy, int(rng.integers(strategy.levels.count)), bool(rng.random() < 0.4))
        if rng.random() < 0.05:
            p = np.array([np.mean(h) if h else 0.0 for h in strategy.history])
            assert np.array_equal(strategy.learnability(), p * (1 - p))


# --- what the episodes started from -----------------------------------------------------------


def test_episode_choices_are_binned_by_the_step_each_episode_started_at():
    choices = EpisodeChoices(every=100, bins=3, annulus_from=10.5)
    for start, target, d, solved in [(0, False, 2.0, True), (50, False, 10.5, False),
                                     (150, True, 11.0, False), (299, True, 12.0, True), (300, True, 12.0, True)]:
        choices.add(start, target, d, solved)
    s = choices.summary()
    assert s["episodes"] == [2, 1, 2]  # an episode begun at the last step joins the last bin
    assert s["target_share"] == [0.0, 1.0, 1.0]
    assert s["distance_median"] == [6.25, 11.0, 12.0]
    assert s["solved_share"] == [0.5, 0.0, 1.0]
    # Exposure counts a curriculum's own task in the annulus (not a target task) too.
    assert s["annulus_share"] == [0.5, 1.0, 1.0]
    assert s["annulus_solved"] == [0, 0, 2]
    empty = EpisodeChoices(every=10, bins=2, annulus_from=10.5).summary()
    assert empty["episodes"] == [0, 0] and empty["distance_median"] == [None, None]
    assert empty["annulus_share"] == [None, None] and empty["annulus_solved"] == [0, 0]


# --- the study end to end, and the curricula for other learners ------------------------------


@pytest.mark.slow
def test_the_study_sweeps_its_arms_and_reports_the_registered_verdict(tmp_path):
    from mediated_transfer.curricula.__main__ import main as curricula_main
    from mediated_transfer.sweep import tracking

    from .test_sweep import _run_cli, fresh_store

    fresh_store(tmp_path)
    common = ["scale=smoke", f"paths.root={tmp_path}", "hydra.sweeper.params.seed=4000",
              "representation=fsr", "env=default", "hydra.searchpath=[pkg://auto_curricula.conf]"]
    cells = "cell=none_0,regular_100,scaffolded_100,dr_0,plr_handover_100"
    _run_cli("experiment=curricula2", "hydra/launcher=basic", cells, *common)
    sweep_dir = tmp_path / "multirun" / "curricula2" / "smoke"
    variant = "env=default,representation=fsr"
    found = sorted(p.relative_to(sweep_dir).parts[0] for p in sweep_dir.glob(f"*/seed=4000/{variant}/result.json"))
    assert found == ["dr_0", "none_0", "plr_handover_100", "regular_100", "scaffolded_100"]
    plr = RunResult.read(sweep_dir / "plr_handover_100" / "seed=4000" / variant)
    assert plr.code["plugins"][0]["target"] == "auto_curricula.handover.PLRHandover"
    assert sum(plr.choices["episodes"]) > 0 and "annulus_share" in plr.choices
    runs = tracking.find_runs(tracking.TrackingSettings(f"sqlite:///{tmp_path / 'mlflow.db'}"), "curricula2",
                              "tags.kind = 'run'")
    assert sorted(r.data.tags["cell"] for r in runs) == found  # its own MLflow experiment

    assert curricula_main([cells, *common]) == 0
    report = (tmp_path / "reports" / "smoke" / "CURRICULA.md").read_text()
    # Nothing is learned at smoke scale: every L_R is the maximum, every ratio 1, no curriculum
    # beats the scaffolding, and the report says so by the registered words.
    assert ("**Q1: does any automatic curriculum, in its own setting, beat the paper's scaffolding?** **NO** "
            "(FSR, default: NO)") in report
    assert "- FSR, default: domain randomisation undecided." in report
    assert "- FSR, default: PLR order of C, hand-over undecided." in report
    assert "**Incomplete: 5 of 5 runs.**" not in report and "## Superseded: the first study" in report
    for name in ("curricula_fsr_default.csv", "curricula_fsr_default_q1.csv", "curricula_fsr_default_q2.csv",
                 "curricula_curves.png", "curricula_choices.png"):
        assert (tmp_path / "reports" / "smoke" / "curricula" / name).stat().st_size > 0


def test_the_rule_words_a_ratio_by_its_interval():
    assert word((0.8, 0.7, 0.95)) == "beats"
    assert word((1.2, 1.05, 1.4)) == "worse"
    assert word((0.9, 0.7, 1.1)) == "undecided"
    assert verdict({"rbf": ["worse", "undecided"], "fsr": ["beats"]}) == ("YES", {"rbf": "NO", "fsr": "YES"})
    assert verdict({"rbf": ["undecided"], "fsr": ["worse"]})[0] == "NO"


def test_one_run_per_arm_gives_no_interval_and_no_decision():
    from mediated_transfer.curricula.measures import compare, time_ratio

    def run(loss, seed=0):
        return RunResult(algorithm="dqn", representation="network", strategy="x", n_source=0, seed=seed,
                         budget=300, steps=[100, 200, 300], mean_reward=[10 - loss / 3] * 3, success_rate=[0.0] * 3,
                         reward_loss=float(loss), time_to_threshold=None, source_phase_end=None,
                         source_tasks_solved=0, wall_time_s=1.0, learning_steps_per_s=1.0)

    one = compare("currot_0", [run(21)], "scaffolded_100", [run(15)])
    assert one.ratio[0] == pytest.approx(1.4) and math.isnan(one.ratio[1]) and one.word == "undecided"
    assert all(math.isnan(v) for v in time_ratio([run(21)], [run(15)], 8.0, 300))
    two = compare("currot_0", [run(21), run(22, 1)], "scaffolded_100", [run(15), run(16, 1)])
    assert two.word == "worse"  # every resample's ratio is above 1


@pytest.mark.slow
@pytest.mark.parametrize("cell", ["dr_0", "reverse_0", "learnability_100"])
def test_sb3_ppo_learns_through_the_wrapper_on_a_curriculum(cell, tmp_path):
    importorskip("stable_baselines3")
    strategy, n_source = cell.rsplit("_", 1)
    spec = RunSpec(algorithm="sb3_ppo", representation="network", strategy=strategy, n_source=int(n_source),
                   strategy_target=plugin_target(strategy), strategy_params=plugin_params(strategy),
                   algorithm_params={"n_steps": 128, "batch_size": 32, "n_epochs": 2}, seed=2,
                   budget=600, eval_points=3, eval_episodes=3, source_pool_size=200, cache_dir=str(tmp_path))
    result = execute_run(spec)
    assert result.learner_stats["learning_steps"] == 600 and len(result.mean_reward) == 3
    # The job records the code version (sweep/job.py); the plugin is in it.
    from mediated_transfer.provenance import code_version

    assert code_version(spec)["plugins"][0]["target"] == spec.strategy_target


def test_a_td_error_curriculum_is_refused_for_a_learner_that_cannot_report_td_errors():
    importorskip("stable_baselines3")
    spec = RunSpec(algorithm="sb3_ppo", representation="network", strategy="plr", n_source=2,
                   strategy_target=plugin_target("plr"), strategy_params=plugin_params("plr"))
    with pytest.raises(ValueError, match="strategy=plr asks for the learner's TD errors"):
        spec.validate()


def plugin_target(name):
    return str(OmegaConf.load(CURRICULA_CONF / "strategy" / f"{name}.yaml")["_target_"])


def plugin_params(name):
    node = OmegaConf.to_container(OmegaConf.load(CURRICULA_CONF / "strategy" / f"{name}.yaml"))
    return {k: v for k, v in node.items() if k not in ("_target_", "name")}


def test_exposure_counts_every_annulus_episode_and_old_records_fall_back_to_target_tasks():
    from mediated_transfer.curricula.measures import exposure, first_annulus_success

    def run(choices):
        return RunResult(algorithm="linear_q", representation="fsr", strategy="x", n_source=0, seed=0,
                         budget=300, steps=[100, 200, 300], mean_reward=[0.0] * 3, success_rate=[0.0] * 3,
                         reward_loss=30.0, time_to_threshold=None, source_phase_end=None, source_tasks_solved=0,
                         wall_time_s=1.0, learning_steps_per_s=1.0, choices=choices)

    new = {"every": 100, "episodes": [3, 1, 0], "target_share": [0.0, 0.0, None],
           "annulus_share": [1 / 3, 1.0, None], "annulus_solved": [0, 1, 0]}
    assert exposure(run(new)) == pytest.approx(0.5)  # (1 + 1) of 4 episodes, by episodes not bins
    assert first_annulus_success(run(new)) == 200  # the end of the first interval with one solved
    old = {"every": 100, "episodes": [2, 2, 0], "target_share": [0.5, 1.0, None]}
    assert exposure(run(old)) == pytest.approx(0.75) and first_annulus_success(run(old)) is None
    assert exposure(run(None)) is None


def test_the_dqn_picks_are_the_two_lowest_geometric_means_of_r_s_ties_in_registered_order():
    from mediated_transfer.curricula.measures import dqn_picks

    order = ["dr_0", "reverse_0", "sfl_0", "currot_0"]
    ratios = {"RBF, default": {"dr_0": 2.0, "reverse_0": 1.0, "sfl_0": 0.5, "currot_0": 4.0},
              "FSR, default": {"dr_0": 0.5, "reverse_0": 1.0, "sfl_0": 2.0, "currot_0": 0.1}}
    # geometric means: dr 1, reverse 1, sfl 1, currot 0.63; ties among the first three by order
    assert dqn_picks(ratios, order) == ["currot_0", "dr_0"]
    # a curriculum without runs in one of the groups cannot be picked
    del ratios["FSR, default"]["currot_0"]
    assert dqn_picks(ratios, order) == ["dr_0", "reverse_0"]
