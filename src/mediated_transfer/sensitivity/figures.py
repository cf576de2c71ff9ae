"""The sensitivity study's figure: each transfer arm's gain against the task."""

from __future__ import annotations

from pathlib import Path

from ..reporting.figures import _pyplot
from .measures import Measures, WorldResult, paper_gains
from .study import Study


def plot(results: list[WorldResult], study: Study, path: Path) -> Path:
    """The gain (L_R ratio, time-to-threshold ratio; lower is a larger gain) of each transfer arm
    against discovery rarity (random policy's success rate) and post-discovery learning time,
    every world on one picture, the paper's gains as dashed lines."""
    plt = _pyplot()
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FuncFormatter, PercentFormatter

    paper = paper_gains()
    fig, axes = plt.subplots(2, 2, figsize=(12, 9), sharey="row")
    markers = {"regular": "o", "scaffolded": "s"}
    colors = plt.get_cmap("tab10")
    for row, (what, label) in enumerate([("reward_loss_ratio", "L_R ratio (transfer / none)"),
                                         ("threshold_time_ratio", "time-to-threshold ratio (transfer / none)")]):
        for col, (x_of, x_label, percent) in enumerate([
                (lambda r: r.random_success, "random policy's success rate on target tasks (discovery rarity)", True),
                (lambda r: r.learning_median, "median steps from first reward to <R> >= 8, without transfer", False)]):
            ax = axes[row, col]
            for k, r in enumerate(results):
                x = x_of(r)
                if x is None or not x > 0:
                    continue
                for cell, gain in r.gains.items():
                    interval = getattr(gain, what)
                    strategy = cell.split("_")[0]
                    # Scaffolded a little to the right, so both arms of a world stay visible.
                    shift = 1.0 if strategy == "regular" else 1.02
                    err = [[max(0.0, interval.value - interval.low)], [max(0.0, interval.high - interval.value)]]
                    ax.errorbar([x * shift], [interval.value], yerr=err, fmt=markers.get(strategy, "^"),
                                color=colors(k % 10), capsize=3, alpha=0.9,
                                mfc=colors(k % 10) if strategy == "regular" else "white")
            for cell, (loss, time) in paper.items():
                if cell in study.transfer_cells:
                    value = loss if row == 0 else time
                    if value is not None:
                        ax.axhline(value, ls="--", lw=1, color="0.4" if cell.startswith("regular") else "0.7")
                        ax.text(1.0, value, f" paper {cell}", transform=ax.get_yaxis_transform(),
                                fontsize=7, va="center", color="0.3")
            ax.axhline(1.0, lw=0.8, color="black")
            if percent:  # rates, on a linear axis (the worlds span a factor of about 4)
                ax.xaxis.set_major_formatter(PercentFormatter(1.0, decimals=2))
            else:
                ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v / 1000:.0f}k"))
            ax.set_xlabel(x_label, fontsize=9)
            if col == 0:
                ax.set_ylabel(label)
            ax.grid(alpha=0.3)

    handles = [Line2D([], [], ls="", marker="o", color=colors(k % 10), label=r.world.option)
               for k, r in enumerate(results)]
    handles += [Line2D([], [], ls="", marker=markers.get(c.split("_")[0], "^"), color="black",
                       mfc="black" if c.startswith("regular") else "white", label=c)
                for c in study.transfer_cells]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8, frameon=False)
    for ax in axes.flat:
        ax.set_ylim(bottom=0)
    cfg = study.config
    fig.suptitle(f"Gain from transfer against the task (issue 13): linear Q(lambda) + RBF, "
                 f"{cfg.scale.budget:,} steps, {len(study.seeds)} seeds per arm\n"
                 f"filled: regular, open: scaffolded; bars: {int(100 * Measures().confidence)} % "
                 "bootstrap intervals; below 1 = transfer helps", fontsize=10)
    fig.tight_layout(rect=(0, 0.12, 1, 0.95))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
