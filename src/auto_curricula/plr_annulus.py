"""Prioritized Level Replay over C plus a fixed set of target-annulus levels (issue 42): PLR's
own setting, where the training levels are drawn from the generator of the evaluation
distribution (Procgen: a fixed set of the test generator's seeds), with the easy tasks of C
beside them. The mechanism is plr.py's, unchanged; only the level set differs (level_sets.py).

Values (conf/strategy/plr_annulus.yaml): PLR's beta = 0.1 and rho = 0.1; ``target_levels`` 200
(Procgen's 200 training levels: two annulus levels for each task of C = 100, so two thirds of
the levels are target tasks); ``level_seed`` 0 (one fixed set for every run). Never done.
"""

from __future__ import annotations

import numpy as np

from mediated_transfer.transfer import StrategyContext

from .level_sets import LevelSet
from .plr import PrioritizedLevelReplay


class PLRAnnulus(PrioritizedLevelReplay):
    """``strategy=plr_annulus`` (conf/strategy/plr_annulus.yaml)."""

    def __init__(self, context: StrategyContext, *, temperature: float, staleness: float,
                 target_levels: int, level_seed: int):
        for key, value in (("target_levels", target_levels), ("level_seed", level_seed)):
            if isinstance(value, bool) or not isinstance(value, int) or value < (1 if key == "target_levels" else 0):
                raise ValueError(f"strategy.{key} must be an integer >= {1 if key == 'target_levels' else 0}, "
                                 f"got {value!r}")
        levels = LevelSet.with_annulus(context, "plr_annulus", target_levels, level_seed)  # C refused by name
        super().__init__(context, temperature=temperature, staleness=staleness)
        replace_levels(self, levels)


def replace_levels(plr: PrioritizedLevelReplay, levels: LevelSet) -> None:
    """Give ``plr`` another level set, with fresh per-level state (plr.py builds its own: it is
    left as the first study's runs computed it)."""
    plr.levels = levels
    plr.seen = np.zeros(levels.count, dtype=bool)
    plr.scores = np.zeros(levels.count)
    plr.last_sampled = np.zeros(levels.count)
