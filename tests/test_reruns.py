"""Committed paper-scale runs reproduce bit for bit with today's code, and every committed run
of the paper's tables is current: the redesigns that kept their curves kept them current
(provenance/translations.json records why)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mediated_transfer.config.spec import spec_from_dict, spec_values
from mediated_transfer.provenance.judge import stale
from mediated_transfer.results import RESULT_FILE, RunResult
from mediated_transfer.run import execute_run

from .optional import needs_deep

MULTIRUN = Path(__file__).resolve().parents[1] / "multirun"


@pytest.mark.slow
@pytest.mark.parametrize("run", ["table3_fsr/paper/scaffolded_15/seed=1"])
def test_a_committed_paper_scale_run_reproduces_bit_for_bit(run):
    # FSR runs take ~12 s at paper scale; RBF and the DQN were checked the same way by hand
    # (docs/reliability.md: provenance), the DQN on the machine that ran its rerun. Algorithm 2's
    # run has a source phase and target-task learning; Algorithm 1's standing short run
    # reproduces its committed fingerprint (test_standing.py).
    stored = RunResult.read(MULTIRUN / run)
    again = execute_run(spec_from_dict(spec_values(stored.config)))
    assert again.mean_reward == stored.mean_reward and again.success_rate == stored.success_rate
    assert (again.first_target_reward_step, again.source_phase_end, again.source_tasks_solved) == (
        stored.first_target_reward_step, stored.source_phase_end, stored.source_tasks_solved)


@pytest.mark.parametrize("table", ["table2_rbf", "table3_fsr", pytest.param("table4_dnn", marks=needs_deep)])
def test_every_committed_run_of_the_papers_tables_is_current(table):
    folders = [p.parent for p in (MULTIRUN / table / "paper").glob(f"*/seed=*/{RESULT_FILE}")]
    assert len(folders) == 220
    found = [f"{f}: {why}" for f in folders if (why := stale(RunResult.read(f)))]
    assert not found, found[:3]
