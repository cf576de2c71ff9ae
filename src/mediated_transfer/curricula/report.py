"""reports/CURRICULA.md: the curricula study's verdicts, tables and figures, built from its runs
by the registered rules (measures.py), and the first study's numbers in a superseded section
(superseded.py). The section between READING_START and READING_END is written by a person after
reading the results and is kept when the report is rebuilt."""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

import pandas as pd

from ..config.worlds import world_of_config
from ..reporting.formats import write_csv
from ..reporting.intervals import format_interval
from ..studies import Written, added_in
from .figures import label, plot_choices, plot_curves
from .measures import (RULE, ArmMeasures, arm_measures, compare, dqn_picks, exposure_correlation, steps_text,
                       time_ratio, verdict)
from .study import DEFAULT_WORLD, NONE, REGULAR, SCAFFOLDED, Study, StudyRuns, collect
from .superseded import superseded_section

REPORT = "CURRICULA.md"
READING_START = "<!-- reading: written by hand, kept when the report is rebuilt -->"
READING_END = "<!-- /reading -->"


def group_measures(study: Study, arms: dict[str, list], failed: dict[str, int],
                   threshold: float) -> dict[str, ArmMeasures | None]:
    """Each arm's measures (None: no runs yet)."""
    return {cell: arm_measures(cell, arms[cell], failed[cell], threshold) if arms[cell] else None
            for cell in study.cells}


def measures_table(study: Study, measures: dict[str, ArmMeasures | None]) -> pd.DataFrame:
    """One group's measures, one row per arm."""
    rows = []
    for cell, m in measures.items():
        if m is None:
            rows.append({"Arm": label(cell), "Runs": f"0/{len(study.seeds)}"})
            continue
        exposure = "-" if m.exposure_median is None else f"{m.exposure_median:.3f}"
        rows.append({
            "Arm": label(cell), "Runs": f"{m.runs}/{len(study.seeds)}" + (f" ({m.failed} failed)" if m.failed else ""),
            "L_R": f"{m.reward_loss_mean:.2f} ± {m.reward_loss_sem:.2f}", "L_R IQM": f"{m.reward_loss_iqm:.2f}",
            "Exposure (median)": exposure if m.exposure_counts_all else f"≥ {exposure}",
            "Time to threshold": steps_text(m.mean_curve_time),
            "Per-run median (reached)": f"{steps_text(m.per_run_time_median)} ({m.reached}/{m.runs})",
            "Never learn": m.never_learn,
            "Annulus first solved (median)": steps_text(m.annulus_solved_median) if m.exposure_counts_all else "-",
            "Discovery (median)": steps_text(m.discovery_median),
            "Hand-over (median, runs)": f"{steps_text(m.done_median)} ({m.done_runs})" if m.done_runs else "-",
        })
    return pd.DataFrame(rows).fillna("")


def decision_table(study: Study, arms: dict[str, list], cells: tuple[str, ...], threshold: float,
                   budget: int) -> tuple[pd.DataFrame, dict[str, str], dict[str, float]]:
    """Each of ``cells`` against scaffolded and regular transfer by the registered rule; its word
    and its r_S (for the DQN's picks) against the scaffolding."""
    rows, words, ratios = [], {}, {}
    for cell in cells:
        if not arms[cell]:
            continue
        row = {"Arm": label(cell)}
        for reference, column in ((SCAFFOLDED, "scaffolded"), (REGULAR, "regular")):
            if arms.get(reference):
                c = compare(cell, arms[cell], reference, arms[reference])
                row[f"L_R / {column} [95 % CI]"] = format_interval(c.ratio)
                row[f"vs {column}"] = f"**{c.word}**"
                if reference == SCAFFOLDED:
                    words[cell], ratios[cell] = c.word, c.ratio[0]
        if arms.get(SCAFFOLDED):
            row["Time to threshold / scaffolded (secondary)"] = format_interval(
                time_ratio(arms[cell], arms[SCAFFOLDED], threshold, budget))
        rows.append(row)
    return pd.DataFrame(rows).fillna(""), words, ratios


class Measured(NamedTuple):
    """The study's measures: per group its arms' measures and decision tables, the DQN's section
    and the first study's superseded section (markdown: both are measured and worded together)."""

    parts: dict[str, dict]
    runs: dict[str, dict[str, list]]
    dqn_section: str
    superseded: str


def measure(study: Study, runs: StudyRuns, dqn: Study, first: Study, progress=print) -> Measured:
    """The linear groups' measures and words by the registered rules (measures.py), the DQN's arms'
    where they have runs, and the first study's superseded section."""
    cfg = study.config
    threshold, budget = float(cfg.threshold), int(cfg.scale.budget)
    (linear, failed), dqn_runs = runs.linear, runs.dqn
    superseded = superseded_section(first, runs.first[0], float(first.config.threshold))
    dqn_section = _dqn_section(dqn, dqn_runs, threshold, budget)
    parts: dict[str, dict] = {}
    for group, arms in linear.items():
        progress(f"curricula: measuring {group} ({sum(len(v) for v in arms.values())} runs)")
        q1, w1, r1 = decision_table(study, arms, study.curricula, threshold, budget)
        q2, w2, _ = decision_table(study, arms, study.handovers, threshold, budget)
        measures = group_measures(study, arms, failed[group], threshold)
        parts[group] = {"arms": measures, "measures": measures_table(study, measures), "q1": q1, "q2": q2,
                        "w1": w1, "w2": w2, "r1": r1}
    return Measured(parts, linear, dqn_section, superseded)


def report(study: Study, measured: Measured, reports_dir: Path) -> Written:
    """CURRICULA.md's text, and its tables and figures (written here)."""
    cfg = study.config
    parts, runs = measured.parts, measured.runs
    out_dir = reports_dir / "curricula"
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for group, part in parts.items():
        stem = group.lower().replace(", ", "_")
        paths += [write_csv(part[k], out_dir / f"curricula_{stem}{suffix}.csv")
                  for k, suffix in (("measures", ""), ("q1", "_q1"), ("q2", "_q2")) if not part[k].empty]
    space = world_of_config(cfg).task_space  # the study's world: its reach and target annulus
    paths.append(plot_curves(runs, float(cfg.threshold), float(cfg.env.success_reward),
                             out_dir / "curricula_curves.png"))
    paths.append(plot_choices(runs, space.reach, space.target_distances, out_dir / "curricula_choices.png"))
    path = reports_dir / REPORT
    text = render(study, parts, runs, _kept_reading(path), "\n\n".join(
        part for part in (measured.dqn_section, measured.superseded) if part))
    return Written({path: text}, paths)


def _dqn_section(dqn: Study, collected: tuple[dict, dict], threshold: float, budget: int) -> str:
    """The DQN's arms (conf/experiment/curricula2_dqn.yaml): its measures and each picked
    curriculum against scaffolded_100 by the registered rule; empty while it has no runs."""
    runs, failed = collected
    (group, arms), = runs.items()
    if not any(arms.values()):
        return ""
    curricula = tuple(c for c in dqn.cells if c not in (NONE, SCAFFOLDED))
    decision, words, _ = decision_table(dqn, arms, curricula, threshold, budget)
    lines = [f"## DQN, {dqn.groups[0].world} world (the registered rule's arms)", ""]
    lines += _incomplete(sum(map(len, arms.values())), len(dqn.seeds) * len(dqn.cells))
    lines += _verdict_lines("Q1 for the DQN: does a picked curriculum beat the scaffolding?", {"DQN": words})
    if not decision.empty:
        lines += [_markdown(decision), ""]
    return "\n".join(lines + [_markdown(measures_table(dqn, group_measures(dqn, arms, failed[group], threshold)))])


def _incomplete(done: int, expected: int) -> list[str]:
    if done >= expected:
        return []
    return [f"**Incomplete: {done} of {expected} runs.** The verdicts below are provisional: they are the "
            "registered rule applied to the runs there are, and may change as the sweep completes; an arm with "
            "fewer than 2 runs has no interval and stays undecided.", ""]


def _verdict_lines(question: str, words: dict[str, dict[str, str]]) -> list[str]:
    overall, per_group = verdict({group: list(w.values()) for group, w in words.items()})
    lines = [f"**{question}** **{overall}** ({'; '.join(f'{g}: {v}' for g, v in per_group.items())}).", ""]
    lines += [f"- {group}: " + (", ".join(f"{label(c)} {v}" for c, v in w.items()) or "no runs yet") + "."
              for group, w in words.items()]
    return lines + [""]


def render(study: Study, parts: dict[str, dict], runs: dict[str, dict[str, list]], reading: str,
           superseded: str) -> str:
    cfg = study.config
    expected = len(study.seeds) * len(study.cells) * len(study.groups)
    done = sum(len(arm) for arms in runs.values() for arm in arms.values())
    seeds = f"{study.seeds[0]}-{study.seeds[-1]}" if len(study.seeds) > 1 else str(study.seeds[0])
    lines = [
        "# Automatic curricula against the paper's scaffolding: a fair test",
        "",
        f"Pre-registered in `conf/experiment/{study.experiment}.yaml` ({added_in(study.registration)}), before its "
        "first run: questions, arms, learners, worlds, seeds, measures, the decision rules and the rule that "
        "picks the DQN's arms. Built by `make curricula` (`python -m mediated_transfer.curricula`) from the runs "
        f"under `{Path(cfg.paths.multirun_dir).name}/{study.experiment}/{cfg.scale.name}/`. Scale `{cfg.scale.name}`: "
        f"{int(cfg.scale.budget):,} learning steps per run, {int(cfg.scale.eval_points)} evaluation points of "
        f"{int(cfg.scale.eval_episodes)} target-task episodes; seeds {seeds} (fresh); learners with Table I's "
        "values; every curriculum in the setting its own paper assumes (docs/curricula.md). The first study's "
        "verdict is withdrawn: see [Superseded](#superseded-the-first-study).",
        "",
    ]
    lines += _incomplete(done, expected)
    lines += ["## Verdicts", ""]
    lines += _verdict_lines("Q1: does any automatic curriculum, in its own setting, beat the paper's scaffolding?",
                            {g: p["w1"] for g, p in parts.items()})
    lines += _verdict_lines("Q2: does a feedback curriculum's order of C, with the paper's hand-over, beat "
                            "Algorithm 2's order?", {g: p["w2"] for g, p in parts.items()})
    lines += [
        RULE,
        "",
        READING_START, reading.strip() or "(to be written after reading the results)", READING_END, "",
        "## Exposure beside L_R", "",
        "Exposure: the median over runs of the share of a run's training episodes whose target lay in the "
        "target annulus (the evaluated tasks), whoever drew the task. The first study ranked its arms in "
        "exactly the order of this share.", "",
        _markdown(_exposure_table(study, parts)), "",
    ]
    correlations = _correlations(study, parts)
    if correlations:
        lines += ["Spearman's rank correlation of median exposure and mean L_R over a group's arms (secondary): "
                  + "; ".join(correlations) + ".", ""]
    lines += _dqn_lines(study, parts)
    for group, part in parts.items():
        lines += [f"## Linear Q(λ) + {group}", ""]
        for key in ("q1", "q2"):
            if not part[key].empty:
                lines += [_markdown(part[key]), ""]
        lines += [_markdown(part["measures"]), ""]
    lines += [
        "L_R: mean ± s.e.m. over runs (0 best, 250 worst); IQM: interquartile mean. Time to threshold: of the "
        f"arm's mean curve, the first evaluation step from which <R> >= {float(cfg.threshold):g} to the end "
        "(the paper's); per run: the median, a run that never gets there counting as slower than any that does. "
        "Never learn: no evaluation point at the threshold. Annulus first solved: the end of the first evaluation "
        "interval in which the run solved an annulus task, whoever drew it. Discovery: the first rewarded "
        "episode of a target task the environment drew. Hand-over: the learning step at which the strategy "
        "gave over to target tasks for good. Ratios: 95 % percentile bootstrap intervals, 10,000 resamples "
        "(reporting/intervals.py). Budget: every arm 500k learning steps, every environment step a learning "
        "step (SFL's scoring episodes are training episodes). Tuning: the learners' Table I values (tuned "
        "without transfer); the curricula's values from their papers, none tuned here.",
        "",
        "## Learning curves", "", "![every arm's mean curve](curricula/curricula_curves.png)", "",
        "## What each curriculum chose", "",
        "![the target distance of the episodes each arm started, and its exposure](curricula/curricula_choices.png)",
        "",
        "Per evaluation interval of each run (result.json `choices`): the target distance of the tasks the "
        "episodes started from, and the exposure (the share of episodes on target-annulus tasks).", "",
    ]
    if superseded:
        lines += [superseded, ""]
    return "\n".join(lines)


def _exposure_table(study: Study, parts: dict[str, dict]) -> pd.DataFrame:
    """Arms as rows, one column per group: 'L_R (exposure)', from the arms' measures."""
    frame = pd.DataFrame({"Arm": [label(c) for c in study.cells]})
    for group, part in parts.items():
        frame[group] = [_loss_and_exposure(part["arms"][c]) for c in study.cells]
    return frame


def _loss_and_exposure(m: ArmMeasures | None) -> str:
    if m is None:
        return "-"
    exposure = "-" if m.exposure_median is None else f"{m.exposure_median:.3f}"
    return f"{m.reward_loss_mean:.2f} ({exposure if m.exposure_counts_all else '≥ ' + exposure})"


def _correlations(study: Study, parts: dict[str, dict]) -> list[str]:
    out = []
    for group, part in parts.items():
        measured = [m for m in part["arms"].values() if m is not None and m.exposure_median is not None]
        rho = exposure_correlation([m.exposure_median for m in measured], [m.reward_loss_mean for m in measured])
        if rho is not None:
            out.append(f"{group} {rho:+.2f} ({len(measured)} arms)")
    return out


def _picks(study: Study, parts: dict[str, dict]) -> list[str]:
    """The registered rule's two curricula for the DQN, from RBF's and FSR's r_S in the default world."""
    ratios = {g: p["r1"] for g, p in parts.items() if g.endswith(f", {DEFAULT_WORLD}")}
    return dqn_picks(ratios, study.curricula) if len(ratios) == 2 else []


def dqn_cells(study: Study) -> list[str]:
    """The DQN sweep's cells: none_0, scaffolded_100 and the two picked curricula. ValueError
    while the linear runs cannot pick them."""
    runs, _ = collect(study)
    cfg = study.config
    parts = {g: {"r1": decision_table(study, arms, study.curricula, float(cfg.threshold),
                                      int(cfg.scale.budget))[2]} for g, arms in runs.items()}
    picks = _picks(study, parts)
    if len(picks) < 2:
        raise ValueError("the DQN's curricula cannot be picked yet: the rule needs RBF's and FSR's default-world "
                         "runs of the curricula and of scaffolded_100")
    return ["none_0", SCAFFOLDED, *picks]


def _dqn_lines(study: Study, parts: dict[str, dict]) -> list[str]:
    picks = _picks(study, parts)
    if not picks:
        return ["The DQN's two curricula (the registered rule: lowest geometric mean of r_S over RBF and FSR in "
                "the default world) cannot be picked yet.", ""]
    return [f"**The DQN's arms** by the registered rule (lowest geometric mean of r_S over RBF and FSR in the "
            f"default world): none_0, scaffolded_100, {picks[0]} and {picks[1]} (`make curricula-dqn`).", ""]


def _markdown(frame: pd.DataFrame) -> str:
    return frame.to_markdown(index=False, colalign=["left"] + ["right"] * (frame.shape[1] - 1))


def _kept_reading(path: Path) -> str:
    if not path.is_file():
        return ""
    match = re.search(re.escape(READING_START) + r"(.*?)" + re.escape(READING_END), path.read_text(), re.S)
    return match.group(1) if match else ""
