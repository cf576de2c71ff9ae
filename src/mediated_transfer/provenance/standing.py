"""The standing short run of each run kind, and its fingerprint.

A run kind (``algorithm/representation/strategy[/lockstep]``, provenance.run_kind) is what one
code digest covers. Its standing run is one fixed, small run of that kind, seconds long, that
still goes through the kind's code: its loop (the project's, a lockstep group of two seeds, or
SB3's), learner updates, the representation, the strategy's source phase and its hand-over to
the target task, and evaluation points. Its fingerprint (fingerprint.py) is what the run
computed, the trained learner's state included. When a refactor moves a kind's digest, the
standing run of the new code either reproduces the fingerprint recorded with the old digest (the
code computes the same: its results carry over, carry_over.py) or it does not (a change of
behaviour, or a short run that no longer reproduces).

What each standing run is lives here, in the provenance package, which no digest covers: so
editing these values changes no digest, only the fingerprints they give (record them again
with ``carry_over --retake``).
"""

from __future__ import annotations

import functools
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

from . import run_digest, run_kind

SCALE = {"budget": 4000, "eval_points": 2, "eval_episodes": 3, "source_pool_size": 100}
"""Small enough for seconds per run (~40 episodes), large enough that DQN and SB3 update their
networks hundreds of times and copy their target networks."""
N_SOURCE = 3
"""C for the strategies that need one: 3 tasks, so that scaffolding's "most similar unsolved
task" (eq. 3) has a choice to make after the first is solved."""
SEED = 3
"""The seed of a single kind's standing run."""
LOCKSTEP_SEEDS = (3, 5)
"""A lockstep kind's standing run is a group of two seeds (the loop interleaves them)."""
GOAL_RADIUS = 4.0
"""The world's goal area, larger than the default 2 (a world variant is config; the world's code
is the same): chance solves the source tasks within the short budget in most standing runs, so
the hand-over to the target task runs too (in 23 of the 30 kinds whose strategy hands over from
C, 29 of their 36 runs; with the default goal about half), and chance rewards some target-task
episodes."""

ALGORITHM_PARAMS: dict[str, dict] = {
    # Replay and exploration scaled to the short budget, so the networks learn in it.
    "dqn": {"learning_starts": 200, "buffer_size": 2000, "epsilon_decay_steps": 1000,
            "target_update_interval": 500},
    "sb3_dqn": {"learning_starts": 200, "buffer_size": 2000, "target_update_interval": 500},
    # PPO's default rollout (2048 steps) would leave a 4000-step run one update.
    "sb3_ppo": {"n_steps": 256, "batch_size": 64, "n_epochs": 2},
}
"""Learner keys beside their defaults (the linear learners' defaults need none)."""

PLUGIN_STRATEGIES: dict[str, tuple[str, dict]] = {
    # The auto_curricula plugin (src/auto_curricula), whose runs are committed (the curricula
    # studies): option name -> (its _target_, its standing parameters). The parameters are its
    # registered ones (auto_curricula/conf/strategy) with the batch sizes scaled down, so that
    # a curriculum that adapts every few dozen episodes adapts within ~40 (ALP-GMM's fits,
    # CURROT's particle updates, the reverse curriculum's iterations, SFL's rebuilt buffer).
    # They are written out here, not read from the yaml files: editing a study's config must
    # not change the standing runs that certify a later refactor.
    "dr": ("auto_curricula.domain_randomisation.DomainRandomisation", {}),
    "alp_gmm": ("auto_curricula.alp_gmm.AlpGmm", {"fit_every": 8, "random_share": 0.2, "k_max": 3}),
    "currot": ("auto_curricula.currot.Currot",
               {"n_particles": 10, "delta": 0.6, "epsilon": 0.75, "update_every": 4}),
    "learnability": ("auto_curricula.learnability.Learnability",
                     {"buffer_share": 0.5, "buffer_size": 2, "window": 3}),
    "learnability_handover": ("auto_curricula.handover.LearnabilityHandover",
                              {"buffer_share": 0.5, "buffer_size": 2, "window": 3}),
    "plr": ("auto_curricula.plr.PrioritizedLevelReplay", {"temperature": 0.1, "staleness": 0.1}),
    "plr_annulus": ("auto_curricula.plr_annulus.PLRAnnulus",
                    {"temperature": 0.1, "staleness": 0.1, "target_levels": 6, "level_seed": 0}),
    "plr_handover": ("auto_curricula.handover.PLRHandover", {"temperature": 0.1, "staleness": 0.1}),
    "reverse": ("auto_curricula.reverse.ReverseCurriculum",
                {"r_min": 0.1, "r_max": 0.9, "new_starts": 2, "old_starts": 1, "rollouts": 2,
                 "walk_steps": 3, "step_std": 0.5, "pool": 20}),
    "sfl": ("auto_curricula.sfl.SamplingForLearnability",
            {"buffer_share": 0.5, "buffer_size": 2, "batch_levels": 4, "rollouts": 2}),
}


@dataclass(frozen=True)
class Kind:
    """A run kind and what its standing run needs beyond its key: a plugin strategy's target
    and parameters."""

    algorithm: str
    representation: str
    strategy: str
    lockstep: bool = False
    strategy_target: str | None = None
    strategy_params: Mapping = field(default_factory=dict, compare=False)

    @property
    def key(self) -> str:
        """Its key in translations.json and fingerprints.json."""
        return run_kind(self.spec(), self.lockstep)

    def spec(self, seed: int = SEED, cache_dir: str | None = None):
        """The RunSpec of its standing run (of ``seed``)."""
        from ..env import WorldConfig
        from ..plugins import owner_class
        from ..run import RunSpec

        spec = RunSpec(algorithm=self.algorithm, representation=self.representation, strategy=self.strategy,
                       strategy_target=self.strategy_target, strategy_params=dict(self.strategy_params),
                       algorithm_params=dict(ALGORITHM_PARAMS.get(self.algorithm, {})), seed=seed,
                       world=WorldConfig(goal_radius=GOAL_RADIUS), cache_dir=cache_dir, **SCALE)
        needs = getattr(owner_class(spec.strategy_class()), "source_tasks", "optional")
        return spec if needs == "none" else replace(spec, n_source=N_SOURCE)

    def digest(self) -> str:
        """Its code digest now."""
        return run_digest(self.spec(), self.lockstep)


def builtin_kinds() -> list[str]:
    """Every run kind of the built-in options: algorithm/representation/strategy[/lockstep]."""
    from ..config.targets import builtin_target
    from ..learners.factory import ALGORITHMS, learner_target
    from ..plugins import owner_class

    found = []
    for algorithm in ALGORITHMS:
        cls = owner_class(learner_target(algorithm))
        own_loop = getattr(cls, "run_loop", None) is not None
        for representation in cls.representations:
            builtin_target("representation", representation)  # exists
            for strategy in ("none", "regular", "scaffolded"):
                found.append(f"{algorithm}/{representation}/{strategy}")
                if not own_loop:
                    found.append(f"{algorithm}/{representation}/{strategy}/lockstep")
    return found


def digests_now(keys: list[str]) -> dict[str, str]:
    """Today's code digest of each kind (``algorithm/representation/strategy[=target][/lockstep]``)."""
    from ..runspec import RunSpec

    out = {}
    for key in keys:
        a, r, s, *lock = key.split("/")
        s, _, target = s.partition("=")
        out[key] = run_digest(RunSpec(algorithm=a, representation=r, strategy=s, n_source=0 if s == "none" else 1,
                                      strategy_target=target or None), bool(lock))
    return out


@functools.cache
def kinds() -> dict[str, Kind]:
    """Every kind with a standing run, by key: the built-in options' (builtin_kinds) and
    the plugin strategies' with every learner of the project's loop (read once per process)."""
    from ..learners.factory import ALGORITHMS, learner_target
    from ..plugins import owner_class

    found = [Kind(*_split(key)) for key in builtin_kinds()]
    for algorithm in ALGORITHMS:
        cls = owner_class(learner_target(algorithm))
        if getattr(cls, "run_loop", None) is not None:  # SB3: no TD errors, and no committed runs
            continue
        for representation in cls.representations:
            for name, (target, params) in PLUGIN_STRATEGIES.items():
                found.append(Kind(algorithm, representation, name, strategy_target=target, strategy_params=params))
    return {kind.key: kind for kind in found}


def standing_fingerprint(kind: Kind, cache_dir: str | None = None) -> str:
    """Run ``kind``'s standing run and return its fingerprint (source tasks are clustered into
    ``cache_dir``, a temporary folder if None)."""
    return standing_fingerprints(kind, cache_dir)[()]


def standing_fingerprints(kind: Kind, cache_dir: str | None = None,
                          leave_outs: tuple[tuple[str, ...], ...] = ()) -> dict[tuple[str, ...], str]:
    """Run ``kind``'s standing run once; its fingerprint in full (key ``()``) and with each of
    ``leave_outs``' fields left out (fingerprint.py)."""
    from .fingerprint import fingerprint

    with tempfile.TemporaryDirectory(prefix="standing-") as tmp:
        cache = cache_dir or tmp
        if kind.lockstep:
            runs = _lockstep_runs([kind.spec(seed, cache) for seed in LOCKSTEP_SEEDS])
        else:
            runs = _single_runs(kind.spec(SEED, cache))
    return {leave_out: fingerprint(runs, leave_out) for leave_out in ((), *leave_outs)}


def _single_runs(spec) -> list:
    from ..run import execute_run

    states: list[dict] = []
    result = execute_run(spec, on_finish=_keep_state(states))
    return [(result, states[0])]


def _lockstep_runs(specs) -> list:
    from ..lockstep.run import RunHooks, execute_lockstep

    states: list[list[dict]] = [[] for _ in specs]
    results = execute_lockstep(specs, [RunHooks(on_finish=_keep_state(s)) for s in states])
    return [(result, s[0]) for result, s in zip(results, states)]


def _keep_state(states: list) -> Callable:
    # The state as the run ends (a state_dict is a copy: later calls cannot change it).
    return lambda learner: states.append(learner.state_dict())


def _split(key: str) -> tuple[str, str, str, bool]:
    algorithm, representation, strategy, *lockstep = key.split("/")
    return algorithm, representation, strategy, bool(lockstep)

