"""What a run's training episodes started from, summarised per evaluation interval: the picture
of what a strategy (a curriculum) chose over the run, against learning steps.

Recorded by the project's run loop for every strategy (``result.json``'s ``choices``): per
interval between evaluation points, the episodes started, the share that were target tasks
(the strategy returned None, or was done), the target distance of the tasks started (median,
10 % and 90 % quantiles: where on the way from the source tasks to the target annulus the
curriculum trained), the share of episodes solved, and the exposure to the evaluated tasks: the
share of episodes whose target lay in the target annulus, whoever drew the task (the
environment or the curriculum: ``target_share`` counts only the environment's draws), and how
many of those were solved (the first bin with one is when the annulus was first solved).
"""

from __future__ import annotations

import numpy as np

COLUMNS = ("episodes", "target_share", "distance_median", "distance_q10", "distance_q90", "solved_share",
           "annulus_share", "annulus_solved")


class EpisodeChoices:
    """Episodes of one run, binned by the learning step they started at (``every`` steps a bin,
    ``bins`` bins: the run's evaluation intervals)."""

    def __init__(self, every: int, bins: int, annulus_from: float):
        """``annulus_from``: the target distance from which a task lies in the target annulus
        (the world's ``mediated_min_distance``)."""
        self.every, self.bins, self.annulus_from = every, bins, annulus_from
        self._rows: list[tuple[int, bool, float, bool]] = []

    def add(self, start_step: int, target_task: bool, distance: float, solved: bool) -> None:
        """An episode that began at ``start_step`` (learning steps before its first step)."""
        self._rows.append((min(start_step // self.every, self.bins - 1), target_task, distance, solved))

    def summary(self) -> dict[str, list]:
        """Per bin: the COLUMNS (None where a bin has no episode; a count: 0), and ``every``."""
        rows = np.array(self._rows, dtype=float).reshape(-1, 4)
        out: dict[str, list] = {name: [] for name in COLUMNS}
        for b in range(self.bins):
            part = rows[rows[:, 0] == b]
            n = len(part)
            out["episodes"].append(n)
            if n == 0:
                for name in COLUMNS[1:]:
                    out[name].append(0 if name == "annulus_solved" else None)
                continue
            q10, q50, q90 = np.quantile(part[:, 2], (0.1, 0.5, 0.9))
            out["target_share"].append(round(float(part[:, 1].mean()), 4))
            out["distance_median"].append(round(float(q50), 3))
            out["distance_q10"].append(round(float(q10), 3))
            out["distance_q90"].append(round(float(q90), 3))
            out["solved_share"].append(round(float(part[:, 3].mean()), 4))
            annulus = part[:, 2] >= self.annulus_from
            out["annulus_share"].append(round(float(annulus.mean()), 4))
            out["annulus_solved"].append(int(part[annulus, 3].sum()))
        return {"every": self.every, **out}
