"""The first curricula study (issue 35, conf/experiment/curricula.yaml), kept in the report as a
superseded section: its numbers recomputed from its committed runs, with the exposure that
explains them, and why its verdict is withdrawn (issue 42)."""

from __future__ import annotations

import pandas as pd

from .figures import label
from .measures import arm_measures
from .study import Study

WHY = (
    "Its verdict (\"does any automatic curriculum beat the paper's scaffolding? NO: all four worse, L_R "
    "ratios 2.6-7.0\") is **withdrawn**: the study could not carry it. Its arms fell in the order of how much "
    "they trained on the evaluated tasks (the exposure below), not of curriculum quality. Its PLR and "
    "learnability sampled C plus a single 'target task' level (one level in 101) where their papers draw "
    "training levels from the evaluation distribution's generator; its reverse curriculum seeded from "
    "replayed old starts, so a third of its seeds snapped back to the goal every iteration (a learner that "
    "solves every task needed a median 321 iterations to reach the annulus, the fixed one 18); and its DR, PLR and learnability "
    "never handed over to target tasks, so it mixed the paper's question (the order of the source tasks) with "
    "how much to train on target tasks. Its raw runs stay committed (`multirun/curricula_<learner>/paper/`); "
    "the reverse runs read stale since the reverse curriculum was fixed."
)


def superseded_section(study: Study, runs: dict[str, dict[str, list]], threshold: float) -> str:
    """The section's markdown from the first study's runs (``runs``: group -> arm -> runs)."""
    frame = pd.DataFrame({"Arm": [label(c) for c in study.cells]})
    for group, arms in runs.items():
        learner = group.split(",")[0]
        exposures, losses = [], []
        for cell in study.cells:
            m = arm_measures(cell, arms[cell], 0, threshold) if arms[cell] else None
            exposures.append("-" if m is None or m.exposure_median is None else
                             ("≥ " if cell.startswith("reverse") else "") + f"{m.exposure_median:.4f}")
            losses.append("-" if m is None else f"{m.reward_loss_mean:.1f}")
        frame[f"Exposure ({learner})"] = exposures
        frame[f"L_R ({learner})"] = losses
    table = frame.to_markdown(index=False, colalign=["left"] + ["right"] * (frame.shape[1] - 1))
    runs_count = sum(len(arm) for arms in runs.values() for arm in arms.values())
    return "\n".join([
        "## Superseded: the first study", "",
        f"Issue 35's study (`conf/experiment/curricula.yaml`, seeds {study.seeds[0]}-{study.seeds[-1]}, "
        f"{runs_count} paper-scale runs, RBF and FSR in the default world). {WHY}", "",
        "Exposure as its runs recorded it: the median over runs of the share of training episodes on target "
        "tasks the environment drew (its record has no column for a curriculum's own annulus tasks, so the "
        "reverse curriculum's share is a lower bound).", "",
        table,
    ])
