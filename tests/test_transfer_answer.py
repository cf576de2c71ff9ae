"""Table V's registered answer (reporting/transfer_answer.py): each branch of the rule on synthetic
runs, the discovery / learning split on known steps, the table without the paper's columns, and
the command on the committed DQN table (where transfer is known to help)."""

from __future__ import annotations

import math

import pytest

from mediated_transfer.metrics import reward_loss, time_to_threshold
from mediated_transfer.reporting.collect import CellRuns
from mediated_transfer.reporting.intervals import format_interval
from mediated_transfer.reporting.tables import TableHeader, table_rows, write_tables
from mediated_transfer.reporting.transfer_answer import Registered, answer, main, measure, outcome_words
from mediated_transfer.reporting.verdicts import ABSENT, HOLDS, OTHER_WAY, UNDECIDED
from mediated_transfer.results import RunResult

STEPS = list(range(20_000, 500_001, 20_000))
CELLS = ["none_0"] + [f"{s}_{n}" for s in ("regular", "scaffolded") for n in (1, 15, 50, 100, 5000)]


def _run(cell: str, seed: int, reached_at: int | None, discovered_at: int | None = None) -> RunResult:
    """<R> 2 before ``reached_at``, 9.5 from it on (None: never); first target reward at ``discovered_at``."""
    curve = [9.5 if reached_at is not None and s >= reached_at else 2.0 for s in STEPS]
    strategy, n = cell.rsplit("_", 1)
    return RunResult(algorithm="sb3_ppo", representation="network", strategy=strategy, n_source=int(n), seed=seed,
                     budget=500_000, steps=STEPS, mean_reward=curve, success_rate=[r / 10 for r in curve],
                     reward_loss=reward_loss(curve), time_to_threshold=time_to_threshold(STEPS, curve),
                     source_phase_end=None, source_tasks_solved=0, wall_time_s=1.0, learning_steps_per_s=1.0,
                     first_target_reward_step=discovered_at)


def _cells(reached: dict[str, list[int | None]]) -> dict[str, CellRuns]:
    return {cell: CellRuns(cell.rsplit("_", 1)[0], int(cell.rsplit("_", 1)[1]),
                           [_run(cell, seed, at, None if at is None else at - 40_000) for seed, at in enumerate(times)])
            for cell, times in reached.items()}


REGISTERED = Registered("table5_ppo", CELLS, 20, Registered.read("table5_ppo", "paper").file)


def test_the_rule_reads_the_rows_and_seeds_the_experiment_registered():
    registered = Registered.read("table5_ppo", "paper")
    assert registered.cells == CELLS and registered.runs_per_row == 20
    with pytest.raises(ValueError, match="--experiment='table9' is unknown; allowed: .*table5_ppo"):
        Registered.read("table9", "paper")
    with pytest.raises(ValueError, match="--scale='huge' is unknown; allowed: .*paper"):
        Registered.read("table5_ppo", "huge")


def test_transfer_helps_when_a_best_row_lies_below_one_and_the_split_says_why():
    # Without transfer half the runs learn at 300k, half never; every transfer row learns at 100k,
    # regular_50 at 80k (the best regular row).
    reached = {c: [100_000] * 20 for c in CELLS[1:]} | {"none_0": [300_000] * 10 + [None] * 10,
                                                        "regular_50": [80_000] * 20}
    m = measure(REGISTERED, _cells(reached))
    assert {r.outcome for r in m.rows} == {HOLDS}
    assert m.best["regular"].cell == "regular_50" and m.best["scaffolded"].cell == "scaffolded_1"  # ties: the first
    text = answer(m.best, m.rows, m.learner)
    assert text.startswith("transfer helps PPO: regular transfer (best N_source = 50")
    split = {s.cell: s for s in m.splits}
    # Discovery 40k before reaching: 260k (or never) without transfer; learning 40k once discovered.
    assert split["none_0"].discovered == 10 and math.isinf(split["none_0"].discovery[0])
    assert split["regular_50"].discovery[0] == 40_000 and split["regular_50"].learning[0] == 40_000
    assert m.finished == 220 and not m.failed


def test_the_typical_run_and_the_source_phase_are_reported_beside_the_rule_and_decide_nothing():
    from dataclasses import replace

    from mediated_transfer.reporting.reproduction.open_question import OpenQuestion, headline

    # Without transfer 11 runs learn at 60k and 9 never: a high mean, a low median. With regular_50
    # every run learns at 140k, after a source phase of 30k: a lower mean, a higher median (the other
    # rows at 160k).
    reached = {c: [160_000] * 20 for c in CELLS[1:]} | {"none_0": [60_000] * 11 + [None] * 9,
                                                        "regular_50": [140_000] * 20}
    cells = _cells(reached)
    cells["regular_50"] = CellRuns("regular", 50, [replace(r, source_phase_end=30_000 + r.seed)
                                                   for r in cells["regular_50"].results])
    m = measure(REGISTERED, cells)
    row = next(r for r in m.rows if r.cell == "regular_50")
    assert row.outcome == HOLDS and row.loss_ratio[2] < 1  # the rule: the mean's interval below 1
    assert row.median_ratio[0] > 1  # the typical run learns later
    split = {s.cell: s for s in m.splits}
    assert split["regular_50"].source_phase == 30_009.5 and split["none_0"].source_phase is None
    assert list(m.losses) == CELLS and len(m.losses["none_0"]) == 20
    line = headline(OpenQuestion(REGISTERED, m))
    assert line.startswith("**Beyond the paper: does transfer help PPO?** (Table V, registered before its runs): "
                           "transfer helps PPO: regular transfer (best N_source = 50")
    assert "regular_50: the source phase ends at 30k (median), the median run discovers the target reward at 100k" in line
    assert line.endswith(f"Outside the rule (added after the runs; it decides nothing), the ratio of median L_R: "
                         f"regular_50 {format_interval(row.median_ratio)}; scaffolded_1 "
                         f"{format_interval(m.best['scaffolded'].median_ratio)}.")


def test_transfer_does_not_help_when_no_row_lies_below_one():
    reached = {c: [100_000] * 20 for c in CELLS} | {"regular_1": [160_000] * 20}
    m = measure(REGISTERED, _cells(reached))
    outcomes = {r.cell: r.outcome for r in m.rows}
    assert outcomes["regular_1"] == OTHER_WAY and outcomes["regular_15"] == ABSENT  # same as none_0
    assert answer(m.best, m.rows, m.learner).startswith("transfer does not help PPO")


def test_a_row_that_holds_outside_the_best_rows_decides_nothing():
    reached = {c: [100_000] * 20 for c in CELLS}
    m = measure(REGISTERED, _cells(reached))
    rows = [r.__class__(**{**r.__dict__, "outcome": HOLDS if r.cell == "scaffolded_15" else r.outcome})
            for r in m.rows]
    assert answer(m.best, rows, "PPO") == ("not decided by the registered rule: scaffolded_15 holds, but no "
                                           "strategy's best row does")


def test_without_transfer_rows_there_is_no_answer_yet():
    m = measure(REGISTERED, _cells({"none_0": [100_000] * 20}))
    assert m.rows == [] and answer(m.best, m.rows, m.learner) == "none yet: no transfer row has finished runs"


def test_each_outcome_has_the_registered_words():
    assert outcome_words(HOLDS, 0.5) == "transfer helps"
    assert outcome_words(OTHER_WAY, 1.5) == "transfer hurts"
    assert outcome_words(UNDECIDED, 0.9) == "undecided (point estimate below 1)"
    assert outcome_words(ABSENT, 1.2) == "undecided (point estimate above 1)"


def test_a_table_the_paper_does_not_have_is_written_without_its_columns(tmp_path):
    cells = _cells({c: [100_000] * 3 for c in ("none_0", "regular_50")})
    summaries = {name: c.summary(__import__("mediated_transfer.metrics").metrics.MetricsConfig())
                 for name, c in cells.items()}
    rows = table_rows(summaries, {n: (c.strategy, c.n_source) for n, c in cells.items()}, [], 20)
    header = TableHeader("Table V", "paper", 500_000, 25, 100, 20, 8.0, 10.0)
    md, csv, tex = write_tables(rows, header, tmp_path, "table5_ppo")
    text = md.read_text()
    assert "| without transfer | 0 | 3/20 |" in text and "(paper)" not in text
    assert "lrrrrr" in tex.read_text() and "lrrrrrrr" not in tex.read_text()


def test_the_command_answers_for_the_committed_dqn_table_and_says_it_is_a_cross_check(tmp_path, capsys):
    out = tmp_path / "answer.md"
    assert main(["--experiment", "table4_dnn", "--out", str(out)]) == 0
    text = out.read_text()
    assert "**Answer (cross-check):** transfer helps the DQN" in text
    assert "for which they were not registered" in text and (tmp_path / "answer.png").is_file()
    assert "| none_0 | 20 | - | 20 |" in text  # every DQN run discovers the target's reward, no source phase
    assert "## Outside the rule: the typical run" in text and "| none_0 | " in text.split("## Outside the rule")[1]


def test_the_command_names_a_missing_sweep_in_one_line(tmp_path):
    with pytest.raises(SystemExit, match="no runs of table5_ppo at scale smoke .*run the sweep first"):
        main(["--scale", "smoke", "--root", str(tmp_path)])


@pytest.mark.slow
def test_reproduction_and_readme_give_table_v_s_answer_only_when_every_run_is_in():
    from mediated_transfer.reporting.reproduction.open_question import OpenQuestion, headline, section

    assert OpenQuestion(REGISTERED, None).status() == (
        "not yet run (0 of 220 runs; `make reproduce-tables EXPERIMENTS=table5_ppo`)")
    reached = {c: [100_000] * 20 for c in CELLS[1:]} | {"none_0": [300_000] * 10 + [None] * 10}
    complete = OpenQuestion(REGISTERED, measure(REGISTERED, _cells(reached)))
    assert complete.status().startswith("transfer helps PPO: regular transfer (best N_source = 1")
    # One seed per row: the rule would "hold" on intervals of one run; the reports give no answer.
    first = OpenQuestion(REGISTERED, measure(REGISTERED, _cells({c: t[:1] for c, t in reached.items()})))
    assert first.status().startswith("running, 11 of 220 runs; the registered answer comes when all are in")
    assert "**Answer:** running, 11 of 220 runs" in "\n".join(section(first))
    assert "transfer helps PPO:" not in "\n".join(section(first)) and "helps" not in headline(first)
    text = "\n".join(section(complete))
    assert "**Answer:** transfer helps PPO" in text and "- regular_1 (best of regular): L_R ratio" in text
    # The split: without transfer half the runs never discover, so the median run never does.
    assert "none_0: the median run never does, then the median run never does (10 of 20 runs learn it)" in (
        headline(complete))
    assert ("regular_1: the median run discovers the target reward at 60k, then the median run learns the pull "
            "in 40k more (20 of 20 runs learn it)") in headline(complete)
