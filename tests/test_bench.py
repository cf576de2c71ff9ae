"""`make bench`'s projection of the paper-scale sweep: what it counts and how it adds up."""

import pytest

from mediated_transfer.bench import projection

from .optional import needs_deep


def test_each_table_has_its_eleven_rows_and_twenty_seeds():
    for table in projection.TABLES:
        cells, seeds = projection.table_rows(table)
        assert seeds == 20
        assert cells[0] == "none_0" and len(cells) == 11 and "scaffolded_5000" in cells


def fake_probe(table, cell, steps_per_s, eval_s=0.5, setup_s=0.2):
    return {"experiment": table, "cell": cell, "steps_per_s": steps_per_s, "eval_s_per_point": eval_s,
            "setup_s": setup_s, "paper_budget": 500_000, "paper_eval_points": 25}


def test_projection_adds_every_run_of_every_row_and_divides_by_the_cores():
    probes = [fake_probe("a", "none_0", 50_000), fake_probe("a", "regular_50", 25_000),
              fake_probe("b", "none_0", 5_000)]
    rows = {"a": (["none_0", "regular_50"], 20), "b": (["none_0"], 10)}
    result = projection.project(probes, rows, cores=2)
    run_a = [0.2 + 10 + 12.5 + projection.JOB_OVERHEAD_S, 0.2 + 20 + 12.5 + projection.JOB_OVERHEAD_S]
    run_b = 0.2 + 100 + 12.5 + projection.JOB_OVERHEAD_S
    a, b = result["tables"]["a"], result["tables"]["b"]
    assert a["runs"] == 40 and b["runs"] == 10
    assert a["cpu_hours"] == pytest.approx(20 * sum(run_a) / 3600)
    assert a["wall_hours"] == pytest.approx(a["cpu_hours"] / 2)
    assert a["slowest_row"] == "regular_50" and a["slowest_run_s"] == pytest.approx(run_a[1])
    assert a["learning_share"] == pytest.approx(20 * 30 / (20 * sum(run_a)))
    assert result["total_wall_hours"] == pytest.approx((20 * sum(run_a) + 10 * run_b) / 2 / 3600)


def test_a_probe_is_a_short_real_run_of_the_tables_configuration():
    probe = projection.probe("table2_rbf", "none_0", 200)
    assert probe["algorithm"] == "linear_q" and probe["probe_steps"] == 200
    assert (probe["paper_budget"], probe["paper_eval_points"]) == (500_000, 25)
    assert probe["steps_per_s"] > 0 and probe["eval_s_per_point"] > 0


def test_the_steady_rate_skips_the_warm_up_and_the_final_evaluation():
    # 1,000 steps/s while warming up (to 2,000), then 500 steps/s; the mark at the end (4,000)
    # also holds the probe's evaluation and is left out.
    marks = {1000: 1.0, 2000: 2.0, 3000: 4.0, 4000: 60.0}
    assert projection.steady_rate(marks, warm_up=2000, budget=4000) == pytest.approx(500.0)
    assert projection.steady_rate(marks, warm_up=0, budget=4000) == pytest.approx(2000 / 3.0)
    assert projection.steady_rate({200: 1.0}, warm_up=0, budget=200) is None


@needs_deep
def test_the_dqn_probe_starts_timing_after_its_warm_up():
    from mediated_transfer.config.compose import compose_config
    from mediated_transfer.config.spec import run_spec

    dqn = run_spec(compose_config(["experiment=table4_dnn", "cell=none_0", "scale=paper"]))
    rbf = run_spec(compose_config(["experiment=table2_rbf", "cell=none_0", "scale=paper"]))
    assert projection.warm_up_steps(dqn) == dqn.algorithm_params["learning_starts"] > 0
    assert projection.warm_up_steps(rbf) == 0


def test_the_ppo_table_projection_adds_setup_learning_evaluation_and_the_jobs_overhead():
    from mediated_transfer.bench import ppo_speed

    p = ppo_speed.project_table(steps_per_s=1000.0, eval_s_per_point=2.0, setup_s=0.5, runs=220, cores=2,
                                budget=500_000, eval_points=25)
    run_s = 0.5 + 500.0 + 50.0 + projection.JOB_OVERHEAD_S
    assert p["run_s"] == pytest.approx(run_s)
    assert p["cpu_hours"] == pytest.approx(220 * run_s / 3600)
    assert p["wall_hours"] == pytest.approx(220 * run_s / 2 / 3600)


@pytest.mark.parametrize("episodes", [0, -3])
def test_the_ppo_bench_refuses_an_evaluation_point_of_no_episodes_before_any_run(episodes, monkeypatch):
    from mediated_transfer.bench import ppo_speed

    # Fails the test if a run starts: the refusal must come first.
    monkeypatch.setattr(ppo_speed, "measure", lambda *a, **k: pytest.fail("a run started"))
    with pytest.raises(ValueError, match=f"eval_episodes .*got {episodes}"):
        ppo_speed.run(eval_episodes=episodes, verbose=False)


@pytest.mark.slow
def test_the_ppo_bench_times_k_environments_against_one_in_one_run():
    pytest.importorskip("stable_baselines3")
    from mediated_transfer.bench import ppo_speed

    result = ppo_speed.run(steps=2048, ks=(1, 2), rounds=1, verbose=False, eval_episodes=5)
    assert set(result["by_k"]) == {1, 2} and result["by_k"][1]["ratio_to_k1"] == 1.0
    assert all(r["steps_per_s"] > 0 for r in result["by_k"].values())
    assert result["table_runs"] == 220 and set(result["table5"]) == {1}
    assert result["table5"][1]["wall_hours"] > 0 and result["eval_s_per_point"] > 0
    # Table V as it runs: its experiment's tuned values, 8 environments, rollouts of 512 x 8.
    assert result["table5_as_run"]["rollout"] == 4096 and result["table5_as_run"]["wall_hours"] > 0
