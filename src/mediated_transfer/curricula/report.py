"""reports/CURRICULA.md: the curricula study's verdict, tables and figures, built from its runs
by the registered rule (measures.py). The section between READING_START and READING_END is
written by a person after reading the results and is kept when the report is rebuilt."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pandas as pd

from ..atomic import atomic_write_text
from ..config.compose import CONF_DIR
from ..env.task_space import TaskSpace
from ..reporting.collect import collect_sweep
from ..reporting.formats import write_csv
from ..reporting.intervals import format_interval
from .figures import label, plot_choices, plot_curves
from .measures import arm_measures, compare, steps_text, time_ratio, verdict
from .study import EXPERIMENT, REGULAR, SCAFFOLDED, Study

REPORT = "CURRICULA.md"
READING_START = "<!-- reading: written by hand, kept when the report is rebuilt -->"
READING_END = "<!-- /reading -->"


def collect(study: Study) -> dict[str, dict[str, list]]:
    """learner -> arm -> its finished runs (registered seeds only), and the failed ones apart."""
    runs, failed = {}, {}
    for learner in study.learners:
        cfg = learner.config
        cells = collect_sweep(learner.sweep_dir, str(cfg.algorithm.name), learner.representation,
                              int(cfg.scale.budget), int(cfg.scale.eval_points), learner.variant,
                              int(cfg.scale.eval_episodes))
        runs[learner.representation] = {c: [r for r in cells[c].results if r.seed in study.seeds]
                                        if c in cells else [] for c in study.cells}
        failed[learner.representation] = {c: len(cells[c].failed) if c in cells else 0 for c in study.cells}
    return runs, failed


def learner_table(study: Study, arms: dict[str, list], failed: dict[str, int],
                  threshold: float) -> pd.DataFrame:
    """The learner's measures, one row per arm."""
    rows = []
    for cell in study.cells:
        results = arms[cell]
        if not results:
            rows.append({"Arm": label(cell), "Runs": f"0/{len(study.seeds)}"})
            continue
        m = arm_measures(cell, results, failed[cell], threshold)
        rows.append({
            "Arm": label(cell), "Runs": f"{m.runs}/{len(study.seeds)}" + (f" ({m.failed} failed)" if m.failed else ""),
            "L_R": f"{m.reward_loss_mean:.2f} ± {m.reward_loss_sem:.2f}", "L_R IQM": f"{m.reward_loss_iqm:.2f}",
            "Time to threshold": steps_text(m.mean_curve_time),
            "Per-run median (reached)": f"{steps_text(m.per_run_time_median)} ({m.reached}/{m.runs})",
            "Never learn": m.never_learn,
            "Discovery (median)": steps_text(m.discovery_median),
            "Learning span (median)": steps_text(m.learning_median),
            "Done (median, runs)": f"{steps_text(m.done_median)} ({m.done_runs})" if m.done_runs else "-",
        })
    return pd.DataFrame(rows).fillna("")


def decision_table(study: Study, arms: dict[str, list], threshold: float,
                   budget: int) -> tuple[pd.DataFrame, dict[str, str]]:
    """Each curriculum against scaffolded and regular transfer by the registered rule, and its
    word against the scaffolding."""
    rows, words = [], {}
    for cell in study.curricula:
        if not arms[cell]:
            continue
        row = {"Curriculum": label(cell)}
        for reference, column in ((SCAFFOLDED, "scaffolded"), (REGULAR, "regular")):
            if arms.get(reference):
                c = compare(cell, arms[cell], reference, arms[reference])
                row[f"L_R / {column} [95 % CI]"] = format_interval(c.ratio)
                row[f"vs {column}"] = f"**{c.word}**"
                if reference == SCAFFOLDED:
                    words[cell] = c.word
        if arms.get(SCAFFOLDED):
            row["Time to threshold / scaffolded (secondary)"] = format_interval(
                time_ratio(arms[cell], arms[SCAFFOLDED], threshold, budget))
        rows.append(row)
    return pd.DataFrame(rows).fillna(""), words


def registration() -> str:
    """The commit that added the study's experiment file (its pre-registration), if git knows it."""
    path = CONF_DIR / "experiment" / f"{EXPERIMENT}.yaml"
    try:
        out = subprocess.run(["git", "log", "--diff-filter=A", "--format=%h (%cs)", "--", str(path)],
                             cwd=CONF_DIR, capture_output=True, text=True, timeout=30).stdout.split()
    except (OSError, subprocess.SubprocessError):
        return "its first commit"
    return " ".join(out[-2:]) if out else "its first commit"


def write_report(study: Study, reports_dir: Path, progress=print) -> list[Path]:
    cfg = study.config
    threshold, budget = float(cfg.threshold), int(cfg.scale.budget)
    max_reward = float(cfg.env.success_reward)
    runs, failed = collect(study)
    out_dir = reports_dir / "curricula"
    out_dir.mkdir(parents=True, exist_ok=True)
    tables, decisions, words = {}, {}, {}
    for learner in runs:
        progress(f"curricula: measuring {learner} ({sum(len(v) for v in runs[learner].values())} runs)")
        tables[learner] = learner_table(study, runs[learner], failed[learner], threshold)
        decisions[learner], words[learner] = decision_table(study, runs[learner], threshold, budget)
    paths = [write_csv(table, out_dir / f"curricula_{learner}.csv") for learner, table in tables.items()]
    paths += [write_csv(table, out_dir / f"curricula_{learner}_decision.csv") for learner, table in decisions.items()]
    space = TaskSpace()
    paths.append(plot_curves(runs, threshold, max_reward, out_dir / "curricula_curves.png"))
    paths.append(plot_choices(runs, space.reach, space.target_distances, out_dir / "curricula_choices.png"))
    report = reports_dir / REPORT
    atomic_write_text(report, render(study, tables, decisions, words, runs, _kept_reading(report)))
    return [report, *paths]


def render(study: Study, tables: dict[str, pd.DataFrame], decisions: dict[str, pd.DataFrame],
           words: dict[str, dict[str, str]],
           runs: dict[str, dict[str, list]], reading: str) -> str:
    cfg = study.config
    overall, per_learner = verdict({learner: list(w.values()) for learner, w in words.items()})
    complete = all(len(arm) == len(study.seeds) for arms in runs.values() for arm in arms.values())
    seeds = f"{study.seeds[0]}-{study.seeds[-1]}" if len(study.seeds) > 1 else str(study.seeds[0])
    lines = [
        "# The field's automatic curricula against the paper's scaffolding",
        "",
        f"Pre-registered in `conf/experiment/{EXPERIMENT}.yaml` ({registration()}), before its first run: "
        "arms, learners, seeds, measures and the decision rule. Built by `make curricula` "
        "(`python -m mediated_transfer.curricula`) from the runs under "
        f"`{Path(cfg.paths.multirun_dir).name}/curricula_<learner>/{cfg.scale.name}/`. Scale `{cfg.scale.name}`: "
        f"{int(cfg.scale.budget):,} learning steps per run, {int(cfg.scale.eval_points)} evaluation points of "
        f"{int(cfg.scale.eval_episodes)} target-task episodes; seeds {seeds} (not the tables' or the tuning's); "
        "learners with Table I's values. The curricula are plugins (`src/auto_curricula`, docs/curricula.md).",
        "",
    ]
    if not complete:
        lines += ["**Incomplete:** not every arm has all its runs yet; the verdict below is provisional.", ""]
    lines += [
        "## Verdict",
        "",
        f"**Does any automatic curriculum beat the paper's scaffolding?** **{overall}** "
        f"({'; '.join(f'{k.upper()}: {v}' for k, v in per_learner.items())}).",
        "",
        "The registered rule: a curriculum *beats* scaffolded transfer (N_source = 100) for a learner when "
        "the 95 % bootstrap interval of its mean L_R over scaffolded's lies entirely below 1, is *worse* "
        "when it lies entirely above 1, and is *undecided* otherwise; the same against regular transfer.",
        "",
    ]
    for learner, w in words.items():
        lines.append(f"- {learner.upper()}: " + ", ".join(f"{label(c)} {v}" for c, v in w.items()) + ".")
    lines += ["", READING_START, reading.strip() or "(to be written after reading the results)", READING_END, ""]
    for learner, table in tables.items():
        lines += [f"## Linear Q(λ) + {learner.upper()}", "", _markdown(decisions[learner]), "", _markdown(table), ""]
    lines += [
        "L_R: mean ± s.e.m. over runs (0 best, 250 worst); IQM: interquartile mean. Time to threshold: of the "
        f"arm's mean curve, the first evaluation step from which <R> >= {float(cfg.threshold):g} to the end "
        "(the paper's); per run: the median, a run that never gets there counting as slower than any that does. "
        "Never learn: no evaluation point at the threshold. Discovery: learning step of the first rewarded "
        "target-task episode (one the environment sampled from the target scenario; a curriculum's own tasks "
        "in the annulus do not count); learning span: from there to the first evaluation point at the "
        "threshold. Ratios: 95 % percentile bootstrap intervals, 10,000 resamples (reporting/intervals.py). "
        "Time / scaffolded is secondary, outside the rule (a mean curve that never stays above the threshold "
        "counts as the budget: a bound). Done: the learning step at which the strategy handed over to target "
        "tasks for good (regular and scaffolded: C solved; the reverse curriculum: a start in the annulus "
        "reached R_min); the others never are.",
        "",
        "## Learning curves",
        "",
        "![every arm's mean curve](curricula/curricula_curves.png)",
        "",
        "## What each curriculum chose",
        "",
        "![the target distance of the episodes each arm started](curricula/curricula_choices.png)",
        "",
        "Per evaluation interval of each run (result.json `choices`): the target distance of the tasks the "
        "episodes started from, and the share of target tasks. Regular and scaffolded transfer draw from C "
        "until it is solved, then target tasks only.",
        "",
    ]
    return "\n".join(lines)


def _markdown(frame: pd.DataFrame) -> str:
    return frame.to_markdown(index=False, colalign=["left"] + ["right"] * (frame.shape[1] - 1))


def _kept_reading(path: Path) -> str:
    if not path.is_file():
        return ""
    match = re.search(re.escape(READING_START) + r"(.*?)" + re.escape(READING_END), path.read_text(), re.S)
    return match.group(1) if match else ""
