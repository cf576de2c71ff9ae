"""What one learning run leaves in its output folder: the source of truth for every table.

``result.json`` holds the run's identity, its resolved config and its metrics;
``curve.csv`` holds the evaluation curve (learning step, mean reward <R>, success rate).
Both are written atomically (temporary file, then rename), so an interrupted run never leaves
a half-written result that a later sweep would mistake for a finished one. How they are encoded
(strict JSON, a checksum) and checked when read back (a damaged run is named, never used): the
``stored`` package. A record only: whether a stored run is reused, recomputed, set aside or
reported stale is judged by provenance/judge.py, which knows the code and the config.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import atomic_write_text
from .metrics import learning_span
from .stored import CURVE_FILE, CURVE_HEADER, RESULT_FILE
from .stored.check import DamagedResult, load
from .stored.codec import encode

__all__ = ["CURVE_FILE", "RESULT_FILE", "DamagedResult", "RunResult"]


RESULTS_FORMAT = 2
"""Version of result.json's layout (2: code version and discovery step recorded)."""


@dataclass
class RunResult:
    algorithm: str
    representation: str
    strategy: str
    n_source: int
    seed: int
    budget: int
    """Learning steps of the run (source and target episodes together)."""
    steps: list[int]
    """Learning steps at which the target task was evaluated."""
    mean_reward: list[float]
    """<R> at each evaluation point."""
    success_rate: list[float]
    reward_loss: float
    """L_R = sum_i (R_max - <R_i>)."""
    time_to_threshold: int | None
    """First evaluation step from which this run's curve stays >= the threshold; None: never."""
    source_phase_end: int | None
    """Learning step at which the last source task was solved; None: never (or N_source=0)."""
    source_tasks_solved: int
    wall_time_s: float
    learning_steps_per_s: float
    learner_stats: dict[str, float] = field(default_factory=dict)
    first_target_reward_step: int | None = None
    """Learning step of the first rewarded target-task (training) episode: when the learner
    discovered the mediated interaction. None: never within the budget."""
    config: dict[str, Any] = field(default_factory=dict)
    """The resolved config of the run."""
    code: dict[str, Any] = field(default_factory=dict)
    """The code that computed it: git commit, dirty tree, digest of the computing sources
    (provenance.code_version)."""
    results_format: int | None = None
    """RESULTS_FORMAT when written; None: written before formats were recorded."""
    failure: str | None = None
    """Why the run was stopped as failed (e.g. its learner diverged); None: it ran its budget.
    A failed run's reward loss is NaN (null in result.json) and it has no time to threshold."""
    choices: dict[str, Any] | None = None
    """What the training episodes started from, per evaluation interval (transfer/choices.py);
    None: not recorded (runs of other loops, or written before it was)."""

    @property
    def failed(self) -> bool:
        return self.failure is not None

    def learning_span(self, threshold: float) -> int | None:
        """Steps from this run's first rewarded target-task episode to its first evaluation
        point with <R> >= threshold (metrics.learning_span)."""
        return learning_span(self.first_target_reward_step, self.steps, self.mean_reward, threshold)

    def write(self, folder: str | os.PathLike) -> Path:
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        lines = [CURVE_HEADER]
        lines += [f"{s},{r!r},{p!r}" for s, r, p in zip(self.steps, self.mean_reward, self.success_rate)]
        atomic_write_text(folder / CURVE_FILE, "\n".join(lines) + "\n")
        # result.json last: its presence marks the run as finished.
        # Strict JSON: a non-finite number (a diverged learner's statistics, a failed run's
        # reward loss) is written as null, an infinite config value as "inf" (stored/codec.py).
        record = json.loads(json.dumps(asdict(self), default=_plain))
        atomic_write_text(folder / RESULT_FILE, encode(record))
        return folder / RESULT_FILE

    @classmethod
    def read(cls, folder: str | os.PathLike) -> "RunResult":
        """The run stored in ``folder``, validated (stored/check.py); DamagedResult (one line:
        the file, what is wrong) if it cannot be trusted."""
        data = load(folder)
        if data.get("reward_loss") is None:  # written as null: not a number
            data["reward_loss"] = math.nan
        return cls(**data)

    @staticmethod
    def exists(folder: str | os.PathLike) -> bool:
        """Whether ``folder`` holds anything under result.json: a finished run, or a damaged one
        (a folder of that name included) that ``read`` names."""
        return os.path.lexists(Path(folder) / RESULT_FILE)


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")

