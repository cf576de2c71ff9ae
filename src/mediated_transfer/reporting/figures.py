"""Figures 3-5: learning curves of regular learning (without transfer) against the fastest
transfer variant of the same learner, mean over runs with SEM bands, and the threshold line.
And the comparison of sweeps: reward loss L_R per table cell, a bar per sweep.

"Fastest" is decided on the measured data, as the paper did on its own: the transfer cell
whose mean curve reaches the threshold first (time to threshold); ties, and cells that never
reach it, are ordered by mean reward loss L_R.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .paper import scheme


@dataclass(frozen=True)
class Curve:
    label: str
    summary: dict
    """metrics.summarise_runs output: steps, mean_curve, sem_curve, n_runs, ..."""


def fastest_transfer(summaries: dict[str, dict], strategies: dict[str, tuple[str, int]]) -> str | None:
    """The cell (among those with a source phase) that reaches the threshold first; None if none ran."""
    candidates = [c for c in summaries if strategies[c][0] != "none"]
    if not candidates:
        return None

    def speed(cell: str) -> tuple[float, float]:
        s = summaries[cell]
        t = s["time_to_threshold"]
        return (math.inf if t is None else t, s["reward_loss_mean"])

    return min(candidates, key=speed)


def cell_label(strategy: str, n_source: int, n_runs: int) -> str:
    what = scheme(strategy) if strategy == "none" else f"{scheme(strategy)}, N_source = {n_source}"
    return f"{what} ({n_runs} run{'' if n_runs == 1 else 's'})"


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    return plt


def plot_curves(curves: list[Curve], threshold: float, max_reward: float, title: str,
                subtitle: str, path: str | Path) -> Path:
    """Mean <R> over learning steps with +/- SEM bands, the threshold as a dashed line."""
    plt = _pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7.0, 4.2), dpi=120)
    for curve, colour in zip(curves, ("tab:blue", "tab:orange", "tab:green", "tab:red")):
        steps = np.asarray(curve.summary["steps"], dtype=float)
        mean = np.asarray(curve.summary["mean_curve"], dtype=float)
        # A single run has no SEM (nan): draw the curve without a band.
        sem = np.nan_to_num(np.asarray(curve.summary["sem_curve"], dtype=float))
        ax.plot(steps, mean, marker="o", markersize=3, color=colour, label=curve.label)
        ax.fill_between(steps, mean - sem, mean + sem, color=colour, alpha=0.25, linewidth=0)
    ax.axhline(threshold, color="black", linestyle="--", linewidth=1,
               label=f"threshold <R> = {threshold:g} ({threshold / max_reward:.0%} success)")
    if max(max(c.summary["steps"]) for c in curves) >= 10_000:
        ax.xaxis.set_major_formatter(plt.FuncFormatter(lambda x, _: f"{x / 1000:g}k"))
    ax.set_xlabel("learning steps")
    ax.set_ylabel("average reward per episode <R>")
    ax.set_ylim(-0.2, max_reward + 0.2)
    ax.set_xlim(left=0)
    # Wrapped so a long subtitle stays inside the figure instead of being cut at its edge.
    ax.set_title("\n".join([title, *textwrap.wrap(subtitle, 90)]), fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    # No timestamp in the file: the same data gives the same bytes.
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)
    return path


@dataclass(frozen=True)
class Bars:
    label: str
    """The sweep: 'baseline' or its variant."""
    mean: list[float]
    """L_R per table cell; nan where the sweep has no runs of the cell."""
    sem: list[float]
    """nan for a single run (no error bar)."""


def plot_loss_bars(cells: list[str], bars: list[Bars], title: str, subtitle: str, path: str | Path) -> Path:
    """Grouped bars: per table cell, one bar per sweep (L_R mean, SEM as error bar)."""
    plt = _pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.0 + len(cells) * (0.3 + 0.3 * len(bars))), 4.2), dpi=120)
    width = 0.8 / len(bars)
    for i, sweep in enumerate(bars):
        # Only the cells this sweep ran: a missing bar must not read as L_R = 0.
        ran = [k for k, m in enumerate(sweep.mean) if not math.isnan(m)]
        x = np.array(ran) - 0.4 + width * (i + 0.5)
        sem = np.array([sweep.sem[k] for k in ran])
        # A single run has no SEM (nan): its bar gets no error bar, not a zero-length one.
        ax.bar(x, [sweep.mean[k] for k in ran], width, color=f"C{i}", label=sweep.label,
               yerr=sem, error_kw={"elinewidth": 1, "capsize": 2})
        for k in sorted(set(range(len(cells))) - set(ran)):
            ax.text(k - 0.4 + width * (i + 0.5), 0, "not run", rotation=90, ha="center", va="bottom",
                    fontsize=7, color=f"C{i}")
    ax.set_xticks(range(len(cells)), cells, rotation=30, ha="right", fontsize=8)
    ax.set_xlim(-0.6, len(cells) - 0.4)
    ax.set_xlabel("table cell (scheme, N_source)")
    ax.set_ylabel("reward loss L_R (mean +/- SEM)")
    ax.set_title("\n".join([*textwrap.wrap(title, 75), *textwrap.wrap(subtitle, 75)]), fontsize=9)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)
    return path


@dataclass(frozen=True)
class RunPanel:
    label: str
    steps: list[list[int]]
    """Each run's evaluation steps."""
    curves: list[list[float]]
    """Each run's <R> at those steps."""


def plot_run_panels(panels: list[RunPanel], threshold: float, max_reward: float, title: str,
                    path: str | Path) -> Path:
    """One panel per group, every run's <R> curve as its own line: where runs are bimodal (some
    never learn), a mean with SEM bands hides what the single curves show. A run that never
    reaches the threshold is drawn in red, a run that does in grey."""
    from ..metrics import first_point_at_threshold

    plt = _pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, len(panels), figsize=(2.9 * len(panels) + 0.6, 3.4), dpi=120,
                             sharex=True, sharey=True, squeeze=False)
    for ax, panel in zip(axes[0], panels):
        failed = 0
        for steps, curve in zip(panel.steps, panel.curves):
            never = first_point_at_threshold(curve, threshold) is None
            failed += never
            ax.plot(steps, curve, color="tab:red" if never else "0.45", linewidth=0.8, alpha=0.8)
        ax.axhline(threshold, color="black", linestyle="--", linewidth=1)
        label = [wrapped for line in panel.label.splitlines() for wrapped in textwrap.wrap(line, 40)]
        ax.set_title("\n".join([*label, f"{len(panel.curves)} runs, {failed} never learn"]), fontsize=8)
        ax.grid(alpha=0.3)
        ax.set_xlabel("learning steps", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.xaxis.set_major_formatter(plt.FuncFormatter(lambda x, _: f"{x / 1000:g}k"))
    axes[0][0].set_ylabel("<R> of each run", fontsize=8)
    axes[0][0].set_ylim(-0.2, max_reward + 0.2)
    axes[0][0].set_xlim(left=0)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)
    return path
