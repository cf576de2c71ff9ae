"""The shape every study shares (studies/): a tiny study of its own, a registration and two
stored runs, built through it as the five real ones are."""

from __future__ import annotations

from pathlib import Path

import pytest

from mediated_transfer.results import RunResult
from mediated_transfer.studies import Study, Written, added_in, build, command, split_options

STEPS = [100, 200, 300, 400]


def _stored(folder: Path, seed: int, curve: list[float]) -> Path:
    run = RunResult("linear_q", "rbf", "none", 0, seed, 400, STEPS, curve, [r / 10 for r in curve],
                    sum(10 - r for r in curve), None, None, 0, 1.0, 1.0)
    return run.write(folder / f"seed={seed}")


def tiny_study(root: Path) -> Study:
    """Registration: a file holding the rule (mean L_R below a bound); runs: the stored results;
    measures: their mean L_R; report: one markdown file with the rule's word beside the claim."""
    registration = root / "registered.txt"
    bound = float(registration.read_text().split("=")[1])

    def report(mean_loss: float) -> Written:
        word = "holds" if mean_loss < bound else "does not hold"  # the rule, beside its claim
        return Written({root / "reports" / "TINY.md": f"# Tiny\n\nMean L_R {mean_loss:.1f}: the claim {word}.\n"})

    return Study("tiny", str(registration),
                 lambda: [RunResult.read(p) for p in sorted((root / "runs").glob("seed=*"))],
                 lambda runs: sum(r.reward_loss for r in runs) / len(runs), report, lambda runs: runs)


def test_a_tiny_study_builds_its_report_through_the_shape(tmp_path, capsys):
    (tmp_path / "registered.txt").write_text("bound=20\n")
    _stored(tmp_path / "runs", 0, [0, 5, 9, 10])  # L_R 16
    _stored(tmp_path / "runs", 1, [0, 9, 10, 10])  # L_R 11
    paths = build(tiny_study(tmp_path))
    report = tmp_path / "reports" / "TINY.md"
    assert paths == [report]
    assert report.read_text() == "# Tiny\n\nMean L_R 13.5: the claim holds.\n"
    captured = capsys.readouterr()
    assert captured.out == f"tiny: {report}\n"
    # Synthetic runs carry no code record: the one judge calls them stale, and the driver says so.
    assert "2 stale" in captured.err
    assert not list(report.parent.glob("*.tmp"))  # written atomically: no temporary file left


def test_the_command_line_says_a_mistake_in_one_line(tmp_path, capsys):
    (tmp_path / "registered.txt").write_text("bound=10\n")
    _stored(tmp_path / "runs", 0, [0, 5, 9, 10])

    def make(args: list[str]) -> Study:
        options, overrides = split_options(args, ("--root",))
        assert overrides == ["scale=smoke"]
        return tiny_study(Path(options["--root"]))

    main = command(make, "the tiny study's help")
    assert main(["--help"]) == 0 and capsys.readouterr().out == "the tiny study's help\n"
    assert main([f"--root={tmp_path}", "scale=smoke"]) == 0
    assert "does not hold" in (tmp_path / "reports" / "TINY.md").read_text()
    with pytest.raises(SystemExit, match="error: unknown option --seeds; allowed: --root"):
        main(["--seeds=3"])


def test_a_registration_is_dated_by_the_commit_that_added_it(tmp_path):
    from mediated_transfer.config.compose import CONF_DIR

    assert added_in(tmp_path / "not_in_git.yaml") == "its first commit"
    dated = added_in(CONF_DIR / "experiment" / "curricula2.yaml")
    assert dated == "its first commit" or dated.endswith(")")  # a copy without git history has no date
