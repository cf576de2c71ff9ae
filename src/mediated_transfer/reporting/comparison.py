"""Sweeps of one experiment side by side (the baseline and its variants): per table cell, each
sweep's runs, reward loss L_R (mean +/- SEM), time to threshold, the discovery / learning split
(median step of the first rewarded target-task episode, and median steps from there to the first
<R> >= threshold), the L_R lost after that first <R> >= threshold, and how far each sweep's L_R
lies from the first sweep's. One pandas DataFrame of texts (Markdown), one of numbers (CSV), and
the bars of the figure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pandas as pd

from ..metrics import loss_after_learning, median_time
from .collect import CellRuns, variant_label
from .figures import Bars
from .formats import MARKDOWN
from .paper import PaperRow, scheme
from .tables import reward_loss_text, steps_text


@dataclass(frozen=True)
class Sweep:
    """The summarised runs of one variant of an experiment."""

    variant: str
    summaries: dict[str, dict]
    """cell -> metrics.summarise_runs of its runs."""
    strategies: dict[str, tuple[str, int]]
    """cell -> (strategy, N_source)."""
    expected_runs: int
    budget: int
    eval_points: int
    splits: dict[str, "Split"]
    """cell -> its runs' discovery / learning split."""

    @property
    def label(self) -> str:
        return variant_label(self.variant)

    @property
    def runs(self) -> int:
        return sum(int(s["n_runs"]) for s in self.summaries.values())


@dataclass(frozen=True)
class Split:
    """When the runs of a cell first solved a target task by chance (discovery), and how long
    they then took to learn the tool skill (learning): medians over runs, a run that never got
    there counted as slower than any that did; None when at least half never did. And how much
    they still lost once learned (after): mean L_R from the first <R> >= threshold to the end,
    over the runs that got there; None when none did."""

    discovery: float | None
    learning: float | None
    after: float | None = None

    @classmethod
    def of(cls, cell: CellRuns, threshold: float, max_reward: float) -> "Split":
        after = [a for r in cell.results
                 if (a := loss_after_learning(r.mean_reward, threshold, max_reward)) is not None]
        return cls(median_time([r.first_target_reward_step for r in cell.results]),
                   median_time([r.learning_span(threshold) for r in cell.results]),
                   sum(after) / len(after) if after else None)

    def text(self) -> str:
        return " / ".join("never" if v is None else f"{v:,.0f}" for v in (self.discovery, self.learning))


def compared_cells(sweeps: list[Sweep], paper: list[PaperRow]) -> list[tuple[str, int]]:
    """(strategy, N_source) of every cell measured by some sweep: the paper's order, then the rest."""
    measured = {}
    for sweep in sweeps:
        measured.update(sweep.strategies)
    known = [(p.strategy, p.n_source) for p in paper if p.cell in measured]
    return known + sorted(set(measured.values()) - set(known))


def reward_loss_difference(summary: dict | None, first: dict | None) -> tuple[float, float] | None:
    """L_R of ``summary`` minus that of ``first`` and its SEM (both SEMs combined as for
    independent runs; nan when either has a single run); None unless both cells ran."""
    if summary is None or first is None:
        return None
    return (summary["reward_loss_mean"] - first["reward_loss_mean"],
            math.hypot(summary["reward_loss_sem"], first["reward_loss_sem"]))


def shown(sweeps: list[Sweep], cells: list[tuple[str, int]]) -> pd.DataFrame:
    """One row per table cell, a group of columns per sweep, as read."""
    m, first = MARKDOWN, sweeps[0]
    columns: dict[str, list[str]] = {"Scheme": [scheme(s) for s, _ in cells],
                                     "N_source": [str(n) for _, n in cells]}
    for sweep in sweeps:
        summaries = [sweep.summaries.get(f"{s}_{n}") for s, n in cells]
        columns[f"Runs ({sweep.label})"] = [
            f"{0 if x is None else x['n_runs']}/{sweep.expected_runs}" for x in summaries]
        columns[f"L_R ({sweep.label})"] = [
            "not run" if x is None else reward_loss_text(x["reward_loss_mean"], x["reward_loss_sem"], m)
            for x in summaries]
        columns[f"Time to threshold ({sweep.label})"] = [
            "" if x is None else steps_text(x["time_to_threshold"]) for x in summaries]
        splits = [sweep.splits.get(f"{s}_{n}") for s, n in cells]
        columns[f"Discovery / learning ({sweep.label})"] = ["" if x is None else x.text() for x in splits]
        columns[f"L_R after learning ({sweep.label})"] = [
            "" if x is None else "-" if x.after is None else f"{x.after:.1f}" for x in splits]
        if sweep is not first:
            differences = [reward_loss_difference(x, first.summaries.get(f"{s}_{n}"))
                           for x, (s, n) in zip(summaries, cells)]
            columns[f"ΔL_R ({sweep.label} - {first.label})"] = [
                "" if d is None else f"{d[0]:+.2f} {m.pm} {'n/a' if math.isnan(d[1]) else f'{d[1]:.2f}'}"
                for d in differences]
    return pd.DataFrame(columns)


def numbers(sweeps: list[Sweep], cells: list[tuple[str, int]]) -> pd.DataFrame:
    """The same as numbers; a sweep's columns end in ``[<variant>]`` (empty: not run, never reached)."""
    first = sweeps[0]
    frame = pd.DataFrame({"scheme": [scheme(s) for s, _ in cells], "strategy": [s for s, _ in cells],
                          "n_source": [n for _, n in cells]})
    for sweep in sweeps:
        summaries = [sweep.summaries.get(f"{s}_{n}") or {} for s, n in cells]
        tag = f" [{sweep.label}]"
        frame["runs" + tag] = [x.get("n_runs", 0) for x in summaries]
        frame["expected_runs" + tag] = sweep.expected_runs
        frame["reward_loss_mean" + tag] = pd.array([x.get("reward_loss_mean") for x in summaries], "Float64")
        frame["reward_loss_sem" + tag] = pd.array([x.get("reward_loss_sem") for x in summaries], "Float64")
        frame["time_to_threshold" + tag] = pd.array([x.get("time_to_threshold") for x in summaries], "Int64")
        splits = [sweep.splits.get(f"{s}_{n}") for s, n in cells]
        frame["discovery_median" + tag] = pd.array([x and x.discovery for x in splits], "Float64")
        frame["learning_median" + tag] = pd.array([x and x.learning for x in splits], "Float64")
        frame["loss_after_learning_mean" + tag] = pd.array([x and x.after for x in splits], "Float64")
        if sweep is not first:
            differences = [reward_loss_difference(x or None, first.summaries.get(f"{s}_{n}"))
                           for x, (s, n) in zip(summaries, cells)]
            frame["reward_loss_difference" + tag] = pd.array([d and d[0] for d in differences], "Float64")
            frame["reward_loss_difference_sem" + tag] = pd.array([d and d[1] for d in differences], "Float64")
    return frame


def reward_loss_bars(sweeps: list[Sweep], cells: list[tuple[str, int]]) -> list[Bars]:
    """Per sweep, L_R mean and SEM of each cell (nan where the sweep did not run it)."""
    bars = []
    for sweep in sweeps:
        summaries = [sweep.summaries.get(f"{s}_{n}") for s, n in cells]
        bars.append(Bars(sweep.label,
                         [math.nan if x is None else x["reward_loss_mean"] for x in summaries],
                         [math.nan if x is None else x["reward_loss_sem"] for x in summaries]))
    return bars


def preamble(table: str, title: str, scale: str, threshold: float, max_reward: float,
             sweeps: list[Sweep]) -> list[str]:
    """Title and notes of the Markdown comparison: what was compared, on which scale."""
    m, first = MARKDOWN, sweeps[0]
    runs = ", ".join(f"{m.code(s.label)} {s.runs} run{'' if s.runs == 1 else 's'}" for s in sweeps)
    schedules = {(s.budget, s.eval_points) for s in sweeps}
    if len(schedules) == 1:
        schedule = (f"{first.budget:,} learning steps per run, {m.reward} at {first.eval_points} "
                    f"evaluation points, so {m.reward_loss} lies in 0 to {first.eval_points * max_reward:g}")
    else:
        schedule = ("the sweeps differ in budget or evaluation points, so their "
                    f"{m.reward_loss} are not on one scale: " + ", ".join(
                        f"{m.code(s.label)} {s.budget:,} steps, {s.eval_points} points" for s in sweeps))
    return [
        f"{title}: {' vs '.join(s.label for s in sweeps)}",
        f"Experiment {m.code(table)}, scale {m.code(scale)}: {schedule}. Sweeps: {runs}. A variant is the "
        f"experiment's config with the overrides it is named after; `baseline` has none.",
        f"{m.reward_loss}: reward loss, mean {m.pm} SEM over runs (lower is better). ΔL_R: a sweep's "
        f"{m.reward_loss} minus that of {m.code(first.label)}, {m.pm} both SEMs combined as for independent "
        f"runs. Time to threshold: learning steps until the mean curve stays at {m.reward} {m.geq} "
        f"{threshold:g} to the end; '-': never. Discovery / learning: median learning step of the "
        f"first rewarded target-task episode / median steps from there to the first {m.reward} {m.geq} "
        f"{threshold:g}, over runs (a run that never got there counts as slower than any; 'never': "
        "half or more never did). L_R after learning: the part of L_R from a run's first "
        f"{m.reward} {m.geq} {threshold:g} to the end (what a learned policy still loses: collapses, "
        "a lower plateau), mean over the runs that got there; '-': none did.",
    ]
