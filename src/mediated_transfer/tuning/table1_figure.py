"""Table I's figure per learner: the objective against each searched key, and the discovery /
learning split of every trial's runs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from .space import SearchSpace, override_value
from .study import DEFAULTS


def seed_columns(trials: pd.DataFrame, name: str) -> list[str]:
    return [c for c in trials.columns if c.startswith(f"{name}.seed_")]


def figure(space: SearchSpace, trials: pd.DataFrame, path: Path) -> Path:
    """Objective against each searched key (defaults and best marked), and the discovery /
    learning split: per seed of every trial, steps to the first rewarded target episode against
    the steps from there to the first <R> >= 8."""
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    panels = len(space.params) + 1
    columns = 3
    rows = math.ceil(panels / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(4.2 * columns, 3.3 * rows), squeeze=False)
    best = trials.loc[~trials["stopped_early"], "objective"].idxmin()
    defaults = trials.index[trials["role"] == DEFAULTS]
    stopped = trials["stopped_early"]
    for ax, p in zip(axes.flat, space.params):
        x = trials[p.key]
        if p.kind == "choice":
            labels = [override_value(c) for c in p.choices]
            position = {_choice_key(c): i for i, c in enumerate(p.choices)}
            x = x.map(lambda v: position[_choice_key(v)])
            x = x + np.random.default_rng(0).uniform(-0.15, 0.15, len(x))  # jitter: see the spread
            ax.set_xticks(range(len(labels)), labels)
            ax.set_xlim(-0.5, len(labels) - 0.5)
        elif p.log:
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels of a short decade overlap
        ax.scatter(x[~stopped], trials.loc[~stopped, "objective"], s=14, color="0.5", label="trials")
        if stopped.any():  # at their lower bound: the true L_R lies at or above the marker
            ax.scatter(x[stopped], trials.loc[stopped, "objective"], s=18, marker="^", facecolors="none",
                       edgecolors="0.4", label="stopped early (L_R at least)")
        # Defaults larger and below the best: both stay visible when the defaults are the best.
        ax.scatter(x[defaults], trials.loc[defaults, "objective"], s=160, marker="*", color="tab:red",
                   label="provisional defaults", zorder=3)
        ax.scatter(x[[best]], trials.loc[[best], "objective"], s=60, marker="*", color="tab:green",
                   label="best", zorder=3)
        ax.set_xlabel(p.key)
        ax.set_ylabel("mean reward loss L_R")
    axes.flat[0].legend(fontsize=7)
    ax = axes.flat[len(space.params)]
    discovery = trials[seed_columns(trials, "first_target_reward_step")].to_numpy(dtype=float)
    span = trials[seed_columns(trials, "learning_span")].to_numpy(dtype=float)
    objective = np.repeat(trials["objective"].to_numpy()[:, None], discovery.shape[1], axis=1)
    shown = ~np.isnan(discovery) & ~np.isnan(span)
    points = ax.scatter(discovery[shown], span[shown], c=objective[shown], s=14, cmap="viridis")
    for index, color, size in ((defaults, "tab:red", 160), ([best], "tab:green", 60)):
        for i in index:
            row = trials.index.get_loc(i)
            ok = shown[row]
            ax.scatter(discovery[row][ok], span[row][ok], s=size, marker="*", color=color, zorder=3)
    # Discovered but never learned: drawn at the budget, so the panel shows both failures.
    budget = max(int(c.split("@")[1]) for c in trials.columns if c.startswith("mean_reward@"))
    stuck = ~np.isnan(discovery) & np.isnan(span)
    ax.scatter(discovery[stuck], np.full(int(stuck.sum()), budget), marker="x", s=14, color="0.6",
               label="never <R> >= 8 (drawn at the budget)")
    ax.legend(fontsize=7, loc="best")
    fig.colorbar(points, ax=ax, label="L_R of the trial")
    ax.set_xlabel("discovery: first rewarded target episode (step)")
    ax.set_ylabel("learning: then to first <R> >= 8 (steps)")
    ran = ~np.isnan(trials[seed_columns(trials, "reward_loss")].to_numpy(dtype=float))  # not: seeds a stopped trial skipped
    ax.set_title(f"per run: {int((np.isnan(discovery) & ran).sum())} of {int(ran.sum())} never rewarded, "
                 f"{int(stuck.sum())} rewarded but never <R> >= 8", fontsize=8)
    for ax in list(axes.flat)[panels:]:
        ax.axis("off")
    fig.suptitle(f"{space.learner}: {len(trials)} trial{'' if len(trials) == 1 else 's'}, tuning seeds "
                 f"{', '.join(c.split('seed_')[1] for c in seed_columns(trials, 'reward_loss'))}")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, metadata={"Software": None})
    plt.close(fig)
    return path


def _choice_key(value):
    """A choice as the figure places it: numbers by value (the CSV spells the choice 0.0 as 0),
    anything else as an override spells it."""
    value = _native(value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return override_value(value)


def _native(value):
    # CSV reads true/false as bools or strings depending on the column; compare them as spelt.
    if isinstance(value, str) and value in ("True", "False"):
        return value == "True"
    return value.item() if isinstance(value, np.generic) else value
