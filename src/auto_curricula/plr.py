"""Prioritized Level Replay (Jiang, Grefenstette and Rocktäschel 2021, Algorithms 1 and 2) over
the levels C + {a target task}.

- Replay decision: with probability |seen| / |levels| replay a seen level, otherwise try an
  unseen one (uniformly); once every level is seen, always replay.
- Replay distribution P = (1 - rho) P_S + rho P_C over the seen levels: P_S by rank of the
  level's score, h(S_i)^(1/beta) with h = 1 / rank; P_C by staleness, proportional to the
  episodes since the level was last sampled.
- Score of a level: its latest episode's mean absolute one-step TD error (the paper's
  "one-step TD error" scoring; the learner's ``td_error``).

The paper's values (conf/strategy/plr.yaml): beta = 0.1, rho = 0.1. Never done: target tasks
are one of the levels it replays.
"""

from __future__ import annotations

import numpy as np

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

from .levels import Levels


class PrioritizedLevelReplay:
    """``strategy=plr`` (conf/strategy/plr.yaml)."""

    source_tasks = "required"
    signals = ("td_error",)
    done = False

    def __init__(self, context: StrategyContext, *, temperature: float, staleness: float):
        if not isinstance(temperature, (int, float)) or not 0 < temperature < 1e6:
            raise ValueError(f"strategy.temperature must be a number > 0, got {temperature!r}")
        if not isinstance(staleness, (int, float)) or not 0 <= staleness <= 1:
            raise ValueError(f"strategy.staleness must be a number in [0, 1], got {staleness!r}")
        self.rng, self.temperature, self.staleness = context.rng, float(temperature), float(staleness)
        self.levels = Levels(context, "plr")
        n = self.levels.count
        self.seen = np.zeros(n, dtype=bool)
        self.scores = np.zeros(n)
        self.last_sampled = np.zeros(n)  # episode count when each level was last sampled
        self.episodes = 0

    @property
    def solved_count(self) -> int:
        return self.levels.solved_count

    def replay_distribution(self) -> np.ndarray:
        """P over all levels (zero for unseen ones)."""
        seen = np.flatnonzero(self.seen)
        order = np.argsort(-self.scores[seen], kind="stable")  # rank 1: the highest score
        ranks = np.empty(len(seen))
        ranks[order] = np.arange(1, len(seen) + 1)
        p_score = np.zeros(self.levels.count)
        p_score[seen] = (1.0 / ranks) ** (1.0 / self.temperature)
        p_score /= p_score.sum()
        p_stale = np.zeros(self.levels.count)
        p_stale[seen] = self.episodes - self.last_sampled[seen]
        if p_stale.sum() == 0:  # one level, just sampled: staleness says nothing
            return p_score
        return (1 - self.staleness) * p_score + self.staleness * p_stale / p_stale.sum()

    def next_task(self):
        unseen = np.flatnonzero(~self.seen)
        if len(unseen) and self.rng.random() >= self.seen.mean():
            index = int(unseen[self.rng.integers(len(unseen))])
        else:
            index = int(self.rng.choice(self.levels.count, p=self.replay_distribution()))
        self.episodes += 1
        self.last_sampled[index] = self.episodes
        return self.levels.hand_out(index)

    def report(self, outcome: EpisodeOutcome) -> None:
        index = self.levels.take(outcome)
        if outcome.td_error is None:
            raise RuntimeError("plr scores levels by the learner's TD error: it needs a learner with td_error "
                               "and a loop that reports it (the project's run loop does; TransferWrapper cannot)")
        self.seen[index] = True
        self.scores[index] = outcome.td_error
