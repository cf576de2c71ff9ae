"""The curricula study's figures: every arm's mean learning curve per group (a learner in a
world), and what each arm's episodes started from over the run (the target distance, and the
exposure: the share of episodes on target-annulus tasks)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..reporting.figures import _pyplot
from ..reporting.intervals import sem
from ..results import RunResult
from .study import NONE, PAPER_ARMS

LABELS = {"none_0": "without transfer", "regular_100": "regular, N=100", "scaffolded_100": "scaffolded, N=100",
          "dr_0": "domain randomisation", "reverse_0": "reverse curriculum", "plr_100": "PLR over C",
          "learnability_100": "learnability over C", "plr_annulus_100": "PLR over C + annulus levels",
          "sfl_0": "SFL (generator)", "alp_gmm_0": "ALP-GMM", "currot_0": "CURROT",
          "plr_handover_100": "PLR order of C, hand-over",
          "learnability_handover_100": "learnability order of C, hand-over"}


def label(cell: str) -> str:
    return LABELS.get(cell, cell)


def _style(cell: str) -> dict:
    # The paper's arms dashed, the curricula solid: the comparison the study asks for.
    return {"linestyle": "--" if cell in PAPER_ARMS else "-", "linewidth": 2.0 if cell == "scaffolded_100" else 1.3}


def plot_curves(runs: dict[str, dict[str, Sequence[RunResult]]], threshold: float, max_reward: float,
                path: Path) -> Path:
    """One panel per group: each arm's mean <R> over its runs, ± s.e.m., against learning steps."""
    plt = _pyplot()
    columns = min(len(runs), 2)
    rows = -(-len(runs) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(6.2 * columns, 4.4 * rows), sharey=True, squeeze=False)
    for ax, (group, arms) in zip(axes.flat, runs.items()):
        for cell, results in arms.items():
            if not results:
                continue
            steps = np.array(results[0].steps)
            curves = np.array([r.mean_reward for r in results])
            mean = curves.mean(axis=0)
            spread = np.array([sem(curves[:, i]) for i in range(curves.shape[1])]) if len(results) > 1 else 0 * mean
            line, = ax.plot(steps, mean, label=f"{label(cell)} ({len(results)})", **_style(cell))
            ax.fill_between(steps, mean - spread, mean + spread, color=line.get_color(), alpha=0.12)
        ax.axhline(threshold, color="grey", linewidth=0.8, linestyle=":")
        ax.set_title(f"linear Q(λ) + {group}")
        ax.set_xlabel("learning steps")
        ax.set_ylim(0, max_reward * 1.02)
        ax.grid(alpha=0.3)
        ax.set_ylabel("<R> on target tasks (mean ± s.e.m.)")
    axes[0][-1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_choices(runs: dict[str, dict[str, Sequence[RunResult]]], reach: float,
                 target_distances: tuple[float, float], path: Path) -> Path:
    """Rows: groups; columns: the arms with a curriculum (not ``none_0``, whose episodes are all
    target tasks). Each panel: the median over runs of the started tasks' median target distance
    per evaluation interval, the runs' mean 10-90 % band, and (right axis) the exposure, the
    share of episodes on target-annulus tasks (a record from before that column: the share of
    the environment's target tasks), against learning steps."""
    plt = _pyplot()
    cells = [c for c in next(iter(runs.values())) if c != NONE]
    fig, axes = plt.subplots(len(runs), len(cells), figsize=(2.9 * len(cells), 2.7 * len(runs)),
                             sharex=True, sharey=True, squeeze=False)
    for row, (group, arms) in enumerate(runs.items()):
        for col, cell in enumerate(cells):
            ax = axes[row][col]
            recorded = [r for r in arms.get(cell, ()) if r.choices]
            ax.axhspan(*target_distances, color="tab:red", alpha=0.08)
            ax.axhline(reach, color="grey", linewidth=0.8, linestyle=":")
            if recorded:
                every = recorded[0].choices["every"]
                bins = np.arange(len(recorded[0].choices["episodes"])) * every + every / 2

                def column(name: str) -> np.ndarray:
                    return np.array([[np.nan if v is None else v for v in r.choices[name]] for r in recorded], dtype=float)

                ax.fill_between(bins, np.nanmean(column("distance_q10"), axis=0),
                                np.nanmean(column("distance_q90"), axis=0), color="tab:blue", alpha=0.2)
                ax.plot(bins, np.nanmedian(column("distance_median"), axis=0), color="tab:blue")
                share = ax.twinx()
                exposure = "annulus_share" if "annulus_share" in recorded[0].choices else "target_share"
                share.plot(bins, np.nanmean(column(exposure), axis=0), color="tab:red", linewidth=1)
                share.set_ylim(0, 1.02)
                share.tick_params(labelsize=7, colors="tab:red")
            if row == 0:
                ax.set_title(label(cell), fontsize=9)
            if col == 0:
                ax.set_ylabel(f"{group}:\ntarget distance", fontsize=8)
            if row == len(runs) - 1:
                ax.set_xlabel("learning steps", fontsize=8)
            ax.tick_params(labelsize=7)
    fig.suptitle("What the episodes started from: target distance (blue: median, 10-90 %), reach (dotted), "
                 "target annulus (shaded); exposure, the share of episodes on annulus tasks (red, right axis)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
