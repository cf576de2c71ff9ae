"""Which code computed a result: definitions only reports call stay out of the digest (and a
run indeed never calls them); results recorded with the digest of whole files stay current."""

from __future__ import annotations

import shutil

import pytest

from mediated_transfer import metrics, results
from mediated_transfer.provenance import COMPUTING_SOURCES, PACKAGE, REPORTING_DEFINITIONS, source_digest, staleness
from mediated_transfer.run import RunSpec, execute_run


def copy_computing_sources(root, extra: tuple[str, ...] = ()) -> None:
    """The package's computing sources (and ``extra`` entries) copied under ``root``, to edit."""
    for entry in COMPUTING_SOURCES + extra:
        if (PACKAGE / entry).is_dir():
            shutil.copytree(PACKAGE / entry, root / entry, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy(PACKAGE / entry, root / entry)


@pytest.mark.parametrize("algorithm,representation", [("linear_q", "rbf"), ("dqn", "network")])
def test_a_run_never_calls_the_definitions_left_out_of_the_digest(monkeypatch, algorithm, representation):
    def called(*args, **kwargs):
        raise AssertionError("a run called a definition that REPORTING_DEFINITIONS leaves out of the digest")

    modules = {"metrics.py": metrics, "results.py": results}
    for file, names in REPORTING_DEFINITIONS.items():
        for name in names:
            owner, _, attr = name.rpartition(".")
            target = getattr(modules[file], owner) if owner else modules[file]
            monkeypatch.setattr(target, attr, called)
    monkeypatch.setattr(results, "learning_span", called)  # the name results.py imports
    params = {"hidden_size": 16, "learning_starts": 32, "buffer_size": 100} if algorithm == "dqn" else {}
    spec = RunSpec(algorithm=algorithm, representation=representation, strategy="regular", n_source=1,
                   budget=200, eval_points=2, eval_episodes=2, source_pool_size=20, algorithm_params=params)
    assert execute_run(spec).failure is None


def test_a_reporting_definition_leaves_the_digest_but_other_code_does_not(tmp_path):
    copy_computing_sources(tmp_path)
    metrics_file = tmp_path / "metrics.py"
    source = metrics_file.read_text()
    edited = source.replace("def learning_span(", "def learning_span_renamed(")
    metrics_file.write_text(edited)  # no longer a listed definition: now it counts
    assert source_digest(tmp_path, "linear_q") != source_digest(algorithm="linear_q")
    metrics_file.write_text(source.replace("return max(0, int(steps[reached]) - int(first_target_reward_step))",
                                           "return 0"))  # inside a listed definition: left out
    assert source_digest(tmp_path, "linear_q") == source_digest(algorithm="linear_q")
    assert source_digest(tmp_path, "linear_q", whole_files=True) != source_digest(algorithm="linear_q", whole_files=True)


def test_results_recorded_with_either_digest_of_this_code_are_current():
    from mediated_transfer.provenance import RESULTS_FORMAT

    for whole in (False, True):
        record = {"digest": source_digest(algorithm="dqn", whole_files=whole), "algorithm": "dqn"}
        assert staleness(record, RESULTS_FORMAT) is None
    assert "computed by other code" in staleness({"digest": "0" * 16, "algorithm": "dqn"}, RESULTS_FORMAT)
