"""Tables and figures from run outputs: built here from synthetic result folders with known
curves, so every number in the table can be checked by hand."""

from __future__ import annotations

import dataclasses

import csv
import io
import subprocess
import sys
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from PIL import Image

from mediated_transfer.sweep import tracking
from mediated_transfer.config.compose import CONF_DIR
from mediated_transfer.metrics import summarise_runs
from mediated_transfer.reporting.__main__ import main as reporting_main
from mediated_transfer.reporting.build import build_report
from mediated_transfer.reporting.collect import collect_sweep
from mediated_transfer.reporting.compare import comparison_stem
from mediated_transfer.reporting.compare import main as compare_main
from mediated_transfer.reporting.compose import compose_experiment as compose_report_config
from mediated_transfer.reporting.figures import fastest_transfer
from mediated_transfer.reporting.paper import paper_rows
from mediated_transfer.results import RunResult

from .test_tracking import fresh_store, synthetic_result

# Smoke scale: budget 200, evaluated at steps 100 and 200, 2 seeds per row.
CURVES = {
    ("none", 0): [[2.0, 4.0], [4.0, 6.0]],      # L_R 14, 10: 12 +/- 2; never reaches 8
    ("regular", 50): [[8.0, 9.0], [6.0, 9.0]],  # L_R 3, 5: 4 +/- 1; mean curve reaches 8 at 200
    ("scaffolded", 15): [[9.0, 10.0]],          # one run only: L_R 1, no SEM; reaches 8 at 100
}


def compose_experiment(root: Path, *overrides: str):
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose("config", overrides=["experiment=table2_rbf", "scale=smoke",
                                            f"paths.root={root}", *overrides])


def write_sweep(sweep_dir: Path, curves=CURVES, **kwargs) -> None:
    for (strategy, n_source), runs in curves.items():
        for seed, curve in enumerate(runs):
            result = synthetic_result(strategy, n_source, seed, curve, (100, 200), **kwargs)
            result.write(sweep_dir / f"{strategy}_{n_source}" / f"seed={seed}")


@pytest.fixture
def built(tmp_path):
    cfg = compose_experiment(tmp_path, "tracking=none")
    write_sweep(Path(cfg.paths.sweep_dir))
    return cfg, build_report(cfg)


def _row(markdown: str, scheme: str, n_source: int) -> list[str]:
    for line in markdown.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if cells[:2] == [scheme, str(n_source)]:
            return cells
    raise AssertionError(f"no row {scheme} {n_source} in\n{markdown}")


def test_markdown_table_has_the_papers_rows_measured_values_and_paper_values(built):
    cfg, report = built
    md = (Path(cfg.paths.reports_dir) / "table2_rbf.md").read_text()
    assert _row(md, "without transfer", 0) == [
        "without transfer", "0", "2/2", "12.00 ± 2.00", "-", "- (0/2)", "105.1 ± 15.08", "~400,000"]
    assert _row(md, "regular transfer", 50) == [
        "regular transfer", "50", "2/2", "4.00 ± 1.00", "200", "150 (2/2)", "28.985 ± 5.33", "~70,000"]
    assert _row(md, "scaffolded transfer", 15)[2:5] == ["1/2", "1.00 ± n/a", "100"]
    assert _row(md, "regular transfer", 5000)[2:4] == ["0/2", "not run"]
    assert "Scale `smoke`: 200 learning steps per run" in md and "not comparable" in md
    assert "2 runs (seeds) per row" in md
    assert report.runs == 5


def test_every_paper_row_appears_once_in_the_papers_order(built):
    cfg, _ = built
    rows = list(csv.DictReader(io.StringIO((Path(cfg.paths.reports_dir) / "table2_rbf.csv").read_text())))
    assert [(r["strategy"], int(r["n_source"])) for r in rows] == [
        (p.strategy, p.n_source) for p in paper_rows("II")]
    regular_50 = next(r for r in rows if r["strategy"] == "regular" and r["n_source"] == "50")
    assert float(regular_50["reward_loss_mean"]) == 4.0 and float(regular_50["reward_loss_sem"]) == 1.0
    assert regular_50["time_to_threshold"] == "200" and regular_50["paper_time_to_threshold"] == "70000"
    assert regular_50["scale"] == "smoke" and regular_50["runs"] == "2"
    never = next(r for r in rows if r["strategy"] == "none")
    assert never["time_to_threshold"] == "" and never["paper_reward_loss_mean"] == "105.1"


def test_latex_table_is_a_booktabs_tabular_with_one_line_per_row(built):
    cfg, _ = built
    tex = (Path(cfg.paths.reports_dir) / "table2_rbf.tex").read_text()
    assert "\\begin{tabular}" in tex and "\\toprule" in tex and "\\bottomrule" in tex
    body = tex.split("\\midrule")[1].split("\\bottomrule")[0].strip().splitlines()
    assert len(body) == len(paper_rows("II"))
    assert "4.00 $\\pm$ 1.00" in tex and "N\\_source" not in tex.split("\\caption")[0]


def test_figure_compares_regular_learning_with_the_fastest_transfer(built):
    cfg, report = built
    assert report.figure == Path(cfg.paths.reports_dir) / "figure4_rbf.png"
    with Image.open(report.figure) as image:
        assert image.format == "PNG" and image.size[0] > 400


def test_fastest_transfer_is_the_first_to_reach_the_threshold_then_lowest_loss():
    steps = [100, 200, 300]
    summaries = {
        "none_0": summarise_runs([[9, 9, 9]], steps),          # fastest, but not a transfer
        "regular_1": summarise_runs([[0, 9, 9]], steps),       # reaches at 200
        "regular_15": summarise_runs([[0, 9, 10]], steps),     # also 200, lower L_R
        "scaffolded_50": summarise_runs([[9, 0, 9]], steps),   # stable only from 300
    }
    strategies = {"none_0": ("none", 0), "regular_1": ("regular", 1), "regular_15": ("regular", 15),
                  "scaffolded_50": ("scaffolded", 50)}
    assert fastest_transfer(summaries, strategies) == "regular_15"
    never = {k: summarise_runs([[0, 1, 2 + i]], steps) for i, k in enumerate(["regular_1", "regular_15"])}
    assert fastest_transfer(never, strategies) == "regular_15"
    assert fastest_transfer({"none_0": summaries["none_0"]}, strategies) is None


def test_runs_of_another_learner_in_the_sweep_folder_are_refused(tmp_path):
    cfg = compose_experiment(tmp_path, "tracking=none")
    write_sweep(Path(cfg.paths.sweep_dir), {("none", 0): [[1.0, 2.0]]}, representation="fsr")
    with pytest.raises(ValueError, match="representation='fsr'.*expects representation='rbf'"):
        build_report(cfg)


def test_runs_of_another_evaluation_schedule_are_refused(tmp_path):
    # The table header states the scale's evaluation points; runs with others must not mix in.
    cfg = compose_experiment(tmp_path, "tracking=none", "scale.budget=300", "scale.eval_points=3")
    synthetic_result("none", 0, 0, (1.0, 2.0, 3.0), (100, 200, 300)).write(Path(cfg.paths.sweep_dir) / "none_0/seed=0")
    synthetic_result("none", 0, 1, (1.0, 2.0), (150, 300)).write(Path(cfg.paths.sweep_dir) / "none_0/seed=1")
    with pytest.raises(ValueError, match="2 evaluation points, but this table expects eval_points=3"):
        build_report(cfg)


def test_variants_in_deeper_folders_are_not_part_of_the_table(tmp_path):
    sweep = tmp_path / "sweep"
    write_sweep(sweep, {("none", 0): [[1.0, 2.0]]})
    synthetic_result("none", 0, 0, (5.0, 5.0), (100, 200)).write(sweep / "none_0/seed=0/algorithm.lambda_=0.5")
    [cell] = collect_sweep(sweep).values()
    assert [r.mean_reward for r in cell.results] == [[1.0, 2.0]]


def test_no_runs_is_a_clear_error_naming_the_command(tmp_path):
    cfg = compose_experiment(tmp_path, "tracking=none")
    with pytest.raises(FileNotFoundError, match="python -m mediated_transfer experiment=table2_rbf scale=smoke"):
        build_report(cfg)


def test_summary_runs_per_cell_carry_the_table_and_figure_and_are_not_duplicated(tmp_path):
    uri = fresh_store(tmp_path / "store")
    cfg = compose_experiment(tmp_path, f"tracking.uri={uri}")
    write_sweep(Path(cfg.paths.sweep_dir))
    build_report(cfg)
    build_report(cfg)  # rebuilding the same data keeps the same summaries
    settings = tracking.TrackingSettings(uri)
    runs = tracking.find_runs(settings, "table2_rbf", f"tags.kind = '{tracking.KIND_SUMMARY}'")
    assert sorted(r.data.tags["cell"] for r in runs) == ["none_0", "regular_50", "scaffolded_15"]
    regular = next(r for r in runs if r.data.tags["cell"] == "regular_50")
    assert regular.data.metrics["reward_loss_mean"] == 4.0 and regular.data.metrics["n_runs"] == 2
    artifacts = {a.path for a in settings.client().list_artifacts(regular.info.run_id)}
    assert artifacts == {"table2_rbf.md", "table2_rbf.csv", "table2_rbf.tex", "figure4_rbf.png"}

    # One more finished run changes the data: the summaries are replaced, not added to.
    synthetic_result("regular", 50, 2, (9.0, 9.0), (100, 200)).write(Path(cfg.paths.sweep_dir) / "regular_50/seed=2")
    build_report(cfg)
    runs = tracking.find_runs(settings, "table2_rbf", f"tags.kind = '{tracking.KIND_SUMMARY}'")
    assert len(runs) == 3
    assert next(r for r in runs if r.data.tags["cell"] == "regular_50").data.metrics["n_runs"] == 3


def test_command_line_builds_the_named_experiments(tmp_path, capsys):
    cfg = compose_experiment(tmp_path, "tracking=none")
    write_sweep(Path(cfg.paths.sweep_dir))
    code = reporting_main(["experiment=table2_rbf", "scale=smoke", f"paths.root={tmp_path}", "tracking=none"])
    assert code == 0
    assert "table2_rbf: 5 runs" in capsys.readouterr().out
    assert (tmp_path / "reports" / "smoke" / "table2_rbf.md").is_file()
    with pytest.raises(SystemExit, match="allowed: curricula, curricula2, curricula2_dqn, dqn_failure_ablation, sensitivity, table2_rbf, table3_fsr, table4_dnn"):
        reporting_main(["experiment=table9"])


# --- variants: runs of other overrides than the table cell and seed ----------------------------

LAMBDA = "algorithm.lambda_=0.5"
VARIANT_CURVES = {
    ("none", 0): [[5.0, 5.0], [3.0, 5.0]],  # L_R 10, 12: 11 +/- 1
    ("regular", 15): [[9.0, 9.0]],          # L_R 2; a cell the baseline (CURVES) did not run
}


def write_variant(sweep_dir: Path, variant: str = LAMBDA, curves=VARIANT_CURVES) -> None:
    for (strategy, n_source), runs in curves.items():
        for seed, curve in enumerate(runs):
            result = synthetic_result(strategy, n_source, seed, curve, (100, 200))
            result.write(sweep_dir / f"{strategy}_{n_source}" / f"seed={seed}" / variant)


def reporting_args(root: Path, *overrides: str) -> list[str]:
    return ["experiment=table2_rbf", "scale=smoke", f"paths.root={root}", "tracking=none", *overrides]


@pytest.fixture
def two_sweeps(tmp_path):
    """The baseline (CURVES) and the variant algorithm.lambda_=0.5 (VARIANT_CURVES) in one sweep folder."""
    sweep_dir = Path(compose_experiment(tmp_path).paths.sweep_dir)
    write_sweep(sweep_dir)
    write_variant(sweep_dir)
    return tmp_path


def test_a_variant_and_the_baseline_give_separate_reports_of_their_own_runs(two_sweeps):
    baseline = build_report(compose_report_config("table2_rbf", reporting_args(two_sweeps)[1:]))
    variant = build_report(compose_report_config("table2_rbf", reporting_args(two_sweeps, LAMBDA)[1:]))
    reports = two_sweeps / "reports" / "smoke"
    assert (baseline.variant, baseline.runs) == ("", 5) and (variant.variant, variant.runs) == (LAMBDA, 3)
    assert variant.tables[0] == reports / "variants" / LAMBDA / "table2_rbf.md"
    assert variant.figure == reports / "variants" / LAMBDA / "figure4_rbf.png" and variant.figure.is_file()

    md = variant.tables[0].read_text()
    assert md.splitlines()[0].endswith(f"variant `{LAMBDA}`") and f"Variant `{LAMBDA}`" in md
    assert _row(md, "without transfer", 0)[2:5] == ["2/2", "11.00 ± 1.00", "-"]
    assert _row(md, "regular transfer", 15)[2:5] == ["1/2", "2.00 ± n/a", "100"]
    assert _row(md, "regular transfer", 50)[2:4] == ["0/2", "not run"]      # baseline only
    assert _row(md, "scaffolded transfer", 15)[2:4] == ["0/2", "not run"]
    rows = list(csv.DictReader(io.StringIO(variant.tables[1].read_text())))
    assert {r["variant"] for r in rows} == {LAMBDA}

    md = (reports / "table2_rbf.md").read_text()
    assert "variant" not in md.splitlines()[0]
    assert _row(md, "without transfer", 0)[2:4] == ["2/2", "12.00 ± 2.00"]
    assert _row(md, "regular transfer", 15)[2:4] == ["0/2", "not run"]      # variant only


def test_a_variant_without_runs_is_one_line_naming_the_variants_that_have_runs(two_sweeps):
    with pytest.raises(SystemExit) as exit_:
        reporting_main(reporting_args(two_sweeps, "algorithm.lambda_=0.9"))
    message = str(exit_.value.code)
    assert "\n" not in message and message.startswith("error: no runs of the variant algorithm.lambda_=0.9 in ")
    assert f"runs there: baseline (5 runs), {LAMBDA} (3 runs)" in message
    assert message.endswith("run the sweep first: python -m mediated_transfer experiment=table2_rbf "
                            f"scale=smoke paths.root={two_sweeps} tracking=none algorithm.lambda_=0.9")


def test_only_variant_runs_is_no_run_of_the_baseline(tmp_path):
    write_variant(Path(compose_experiment(tmp_path).paths.sweep_dir))
    with pytest.raises(SystemExit, match=rf"no runs of the baseline in .*\(runs there: {LAMBDA} \(3 runs\)\)"):
        reporting_main(reporting_args(tmp_path))


def test_variant_summaries_in_mlflow_are_apart_from_the_baselines(two_sweeps):
    uri = fresh_store(two_sweeps / "store")
    for overrides in ([], [LAMBDA]):
        args = [a for a in reporting_args(two_sweeps, f"tracking.uri={uri}", *overrides)[1:] if a != "tracking=none"]
        build_report(compose_report_config("table2_rbf", args))
    runs = tracking.find_runs(tracking.TrackingSettings(uri), "table2_rbf", f"tags.kind = '{tracking.KIND_SUMMARY}'")
    assert sorted((r.data.tags["variant"], r.data.tags["cell"]) for r in runs) == [
        (LAMBDA, "none_0"), (LAMBDA, "regular_15"),
        ("baseline", "none_0"), ("baseline", "regular_50"), ("baseline", "scaffolded_15")]
    variant_none = next(r for r in runs if r.data.tags["variant"] == LAMBDA and r.data.tags["cell"] == "none_0")
    assert variant_none.data.metrics["reward_loss_mean"] == 11.0
    assert LAMBDA in variant_none.data.tags["mlflow.runName"]


def test_compare_writes_one_table_and_one_figure_of_both_sweeps(two_sweeps, capsys):
    assert compare_main([*reporting_args(two_sweeps), "--variant", LAMBDA]) == 0
    out = two_sweeps / "reports" / "smoke" / "compare"
    md, csv_file, png = (out / f"table2_rbf__baseline__vs__{LAMBDA}.{ext}" for ext in ("md", "csv", "png"))
    assert f"{md}, {csv_file}, {png}" in capsys.readouterr().out
    rows = {(r["strategy"], r["n_source"]): r for r in csv.DictReader(io.StringIO(csv_file.read_text()))}
    assert list(rows) == [("none", "0"), ("regular", "15"), ("regular", "50"), ("scaffolded", "15")]
    none = rows["none", "0"]
    assert float(none["reward_loss_mean [baseline]"]) == 12.0 and float(none[f"reward_loss_mean [{LAMBDA}]"]) == 11.0
    assert float(none[f"reward_loss_difference [{LAMBDA}]"]) == -1.0
    assert none["loss_after_learning_mean [baseline]"] == ""  # no run reached <R> >= 8
    assert rows["regular", "50"][f"runs [{LAMBDA}]"] == "0" and rows["regular", "50"][f"reward_loss_mean [{LAMBDA}]"] == ""
    assert _row(md.read_text(), "without transfer", 0) == [
        "without transfer", "0", "2/2", "12.00 ± 2.00", "-", "never / never", "-",
        "2/2", "11.00 ± 1.00", "-", "never / never", "-", "-1.00 ± 2.24"]
    with Image.open(png) as image:
        assert image.format == "PNG"


def test_compare_on_the_seeds_given_with_the_discovery_learning_split(tmp_path, capsys):
    sweep_dir = Path(compose_experiment(tmp_path).paths.sweep_dir)
    # (curve at steps 100 and 200, first rewarded target episode): learning = first <R> >= 8 - discovery;
    # L_R after learning: 10 - <R> summed from the first <R> >= 8 on, mean over the runs that got there.
    runs = {"": [([2.0, 9.0], 50), ([8.0, 9.0], 20), ([0.0, 0.0], None)],  # learning 150, 80, never; after 1, 3, -
            LAMBDA: [([9.0, 10.0], 10), ([0.0, 8.0], 150)]}                 # learning 90, 50; after 1, 2
    for variant, seeds in runs.items():
        for seed, (curve, discovery) in enumerate(seeds):
            result = dataclasses.replace(synthetic_result("none", 0, seed, curve, (100, 200)),
                                         first_target_reward_step=discovery)
            result.write(sweep_dir / "none_0" / f"seed={seed}" / variant)

    assert compare_main([*reporting_args(tmp_path), "--variant", LAMBDA]) == 0
    out = tmp_path / "reports" / "smoke" / "compare"
    row = _row((out / f"table2_rbf__baseline__vs__{LAMBDA}.md").read_text(), "without transfer", 0)
    assert row[2] == "3/2" and row[5] == "50 / 150"  # the never-rewarded run counts as slowest
    assert row[6] == "2.0"  # the run that never learned is not part of it

    assert compare_main([*reporting_args(tmp_path), "--variant", LAMBDA, "--seeds", "0-1"]) == 0
    md = out / f"table2_rbf__baseline__vs__{LAMBDA}__seeds_0-1.md"
    assert str(md) in capsys.readouterr().out
    row = _row(md.read_text(), "without transfer", 0)
    assert row[2:7] == ["2/2", "6.00 ± 3.00", "200", "35 / 115", "2.0"]  # seeds 0 and 1 only
    assert row[7:] == ["2/2", "6.50 ± 5.50", "200", "80 / 70", "1.5", "+0.50 ± 6.26"]
    for bad in ("9-x", "-1"):
        with pytest.raises(SystemExit, match=r"^error: --seeds .*give a range like 0-9"):
            compare_main([*reporting_args(tmp_path), "--variant", LAMBDA, "--seeds", bad])
    with pytest.raises(SystemExit, match=r"^error: --seeds 7: baseline has no finished run of these seeds$"):
        compare_main([*reporting_args(tmp_path), "--variant", LAMBDA, "--seeds", "7"])


def test_a_comparison_of_many_long_variants_has_a_valid_distinct_file_name(tmp_path):
    labels = ["baseline", *(f"tuned=linear_q_fsr_round2,representation.tool_origin_high={k},"
                            "representation.tool_target_high=24" for k in range(5))]
    stem = comparison_stem("table3_fsr", labels, list(range(10)))
    assert len(stem) <= 240 and stem.startswith("table3_fsr__baseline__vs__tuned=linear_q_fsr_round2")
    assert stem != comparison_stem("table3_fsr", labels[:-1] + ["baseline2"], list(range(10)))
    (tmp_path / f"{stem}.png").write_bytes(b"")  # the file system takes it
    short = comparison_stem("table2_rbf", ["baseline", LAMBDA], [0, 1, 2])
    assert short == f"table2_rbf__baseline__vs__{LAMBDA}__seeds_0-2"  # short names are unchanged


def test_compare_of_a_variant_without_runs_names_the_variants_present(two_sweeps):
    with pytest.raises(SystemExit, match=rf"^error: no runs of the variant algorithm.lambda_=0.9 .*{LAMBDA} \(3 runs\)"):
        compare_main([*reporting_args(two_sweeps), "--variant", "algorithm.lambda_=0.9"])


# --- the command line: one-line errors, each line once -----------------------------------------


def test_a_mistyped_scale_is_a_one_line_error_with_exit_code_1():
    done = subprocess.run([sys.executable, "-m", "mediated_transfer.reporting", "experiment=table2_rbf", "scale=smok"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr == "error: scale=smok: no such option; allowed: paper, quick, smoke\n"


def test_an_unknown_key_is_a_one_line_error_naming_the_keys_next_to_it():
    with pytest.raises(SystemExit) as exit_:
        reporting_main(["experiment=table2_rbf", "scale=smoke", "algorithm.lamda=0.5"])
    message = str(exit_.value.code)
    assert "\n" not in message
    assert message == "error: unknown key 'algorithm.lamda'; did you mean 'algorithm.lambda_'?"


def test_each_report_line_is_printed_once(tmp_path, capfd):
    write_sweep(Path(compose_experiment(tmp_path).paths.sweep_dir))
    assert reporting_main(reporting_args(tmp_path)) == 0
    out, err = capfd.readouterr()
    assert (out + err).count("table2_rbf: 5 runs") == 1 and err == ""


def test_every_experiment_reports_the_variant_where_it_applies_and_says_where_not(two_sweeps, capsys):
    # algorithm.lambda_ is a key of linear Q(lambda) (Tables II, III), not of the DQN (Table IV).
    assert reporting_main(reporting_args(two_sweeps, LAMBDA)[1:]) == 0
    out, err = capsys.readouterr()
    assert out.startswith(f"table2_rbf [{LAMBDA}]: 3 runs -> ") and out.count("\n") == 1
    assert "skipped: table3_fsr: no runs of the variant" in err
    assert "skipped: table4_dnn: unknown key 'algorithm.lambda_'; keys here: learning_rate, gamma" in err


def test_runs_of_other_code_are_reported_stale_with_how_to_recompute(tmp_path, capsys):
    cfg = compose_experiment(tmp_path, "tracking=none")
    write_sweep(Path(cfg.paths.sweep_dir))
    folder = Path(cfg.paths.sweep_dir) / "regular_50" / "seed=1"
    stale = RunResult.read(folder)
    stale.code = {**stale.code, "commit": "f" * 40, "digest": "0" * 16}  # as if other code wrote it
    stale.write(folder)
    assert reporting_main(reporting_args(tmp_path)) == 0
    out, err = capsys.readouterr()
    assert "table2_rbf: 5 runs (1 stale) -> " in out
    assert "regular_50 seed=1: computed by other code: commit ffffffffff" in err and "rerun_stale=true" in err
    md = (Path(cfg.paths.reports_dir) / "table2_rbf.md").read_text()
    assert "1 of the runs were computed by other code than the current" in md


def test_runs_evaluated_on_other_episodes_than_the_scale_states_are_refused(tmp_path):
    # Changing eval_episodes in a scale file must not relabel older runs in the table header.
    cfg = compose_experiment(tmp_path, "tracking=none")
    write_sweep(Path(cfg.paths.sweep_dir), {("none", 0): [[1.0, 2.0]]})
    folder = Path(cfg.paths.sweep_dir) / "none_0" / "seed=0"
    result = RunResult.read(folder)
    result.config = {"scale": {"eval_episodes": int(cfg.scale.eval_episodes) + 3}}
    result.write(folder)
    with pytest.raises(ValueError, match=r"evaluated on \d+ episodes per point, but this table states "
                                         r"scale.eval_episodes=\d+"):
        build_report(cfg)
