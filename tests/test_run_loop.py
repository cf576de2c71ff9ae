"""The one run loop (issue 43): every learner's run is recorded by recorder.py's RunRecorder, a
single run is a lockstep group of one, TD-error strategies run in CPU groups, every loop records
its episode choices, and only the job writes a result's code version."""

from __future__ import annotations

import pytest

from mediated_transfer.lockstep.run import execute_lockstep
from mediated_transfer.provenance.fingerprint import COMPUTED, fingerprint
from mediated_transfer.run import RunSpec, execute_run

TINY = dict(budget=600, eval_points=3, eval_episodes=3, source_pool_size=50)


class CountingTD:
    """A strategy that only hears target episodes with their TD errors (its own class state per
    seed: each run builds one)."""

    source_tasks = "optional"
    signals = ("td_error",)
    heard: dict = {}

    def __init__(self, context):
        self.key = context.rng.integers(1 << 30)
        CountingTD.heard[self.key] = []

    def next_task(self):
        return None

    def report(self, outcome):
        CountingTD.heard[self.key].append((outcome.length, outcome.step, outcome.td_error))

    @property
    def done(self):
        return False


def _spec(seed, **changes):
    values = dict(algorithm="linear_q", representation="rbf", strategy="regular", n_source=2, seed=seed, **TINY)
    return RunSpec(**{**values, **changes})


def _computed(result) -> dict:
    return {key: getattr(result, key) for key in COMPUTED}


def test_a_linear_lockstep_group_records_the_single_runs_choices(tmp_path):
    specs = [_spec(seed, cache_dir=str(tmp_path)) for seed in (1, 2)]
    grouped = execute_lockstep(specs)
    for spec, result in zip(specs, grouped):
        single = execute_run(spec)
        assert result.choices is not None and sum(result.choices["episodes"]) > 0
        assert _computed(result) == _computed(single)  # choices included, bit for bit


def test_a_td_error_strategy_runs_in_a_cpu_group_with_the_single_runs_curves():
    specs = [_spec(seed, strategy="counting", strategy_target=f"{__name__}.CountingTD", n_source=0)
             for seed in (1, 2)]
    CountingTD.heard = {}
    grouped = execute_lockstep(specs, device="cpu")
    heard_grouped = sorted(CountingTD.heard.values())
    CountingTD.heard = {}
    singles = [execute_run(spec) for spec in specs]
    assert sorted(CountingTD.heard.values()) == heard_grouped  # the same episodes and TD errors
    assert all(td is not None and td >= 0 for episodes in heard_grouped for _, _, td in episodes)
    for result, single in zip(grouped, singles):
        assert _computed(result) == _computed(single)


def test_the_run_loop_leaves_the_code_version_to_the_job():
    assert execute_run(_spec(1, strategy="none", n_source=0)).code == {}


def test_a_fingerprint_can_leave_out_a_field_as_a_run_that_did_not_record_it():
    result = execute_run(_spec(1, strategy="none", n_source=0))
    full = fingerprint([(result, {})])
    result.choices, before = None, result.choices
    without = fingerprint([(result, {})])
    result.choices = before
    assert fingerprint([(result, {})], leave_out=("choices",)) == without != full
    with pytest.raises(ValueError, match="cannot leave out"):
        fingerprint([(result, {})], leave_out=("wall_time_s",))
