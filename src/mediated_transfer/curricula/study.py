"""The curricula study as its experiment file defines it: learners, arms, seeds, run folders."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from omegaconf import DictConfig

from hydra.core.override_parser.overrides_parser import OverridesParser

from ..config.compose import compose_config, prepare_overrides
from ..reporting.compose import variant_of
from ..sweep import planned_jobs

EXPERIMENT = "curricula"
SEARCHPATH = "hydra.searchpath=[pkg://auto_curricula.conf]"
"""Where the curricula's options live (a plugin's config folder, as a user's would)."""
LEARNERS = ("rbf", "fsr")
"""The registered learners: linear Q(lambda) on each representation."""
NONE, REGULAR, SCAFFOLDED = "none_0", "regular_100", "scaffolded_100"
PAPER_ARMS = (NONE, REGULAR, SCAFFOLDED)
"""The paper's arms; every other arm of the sweep is an automatic curriculum."""


@dataclass(frozen=True)
class Learner:
    representation: str
    config: DictConfig
    """The composed experiment for this learner (scale, paths, threshold, Hydra's part)."""
    sweep_dir: Path
    variant: str
    """The runs' folder below seed=<k>/ (the learner's override: representation=<r>)."""


@dataclass(frozen=True)
class Study:
    learners: tuple[Learner, ...]
    cells: tuple[str, ...]
    seeds: tuple[int, ...]

    @property
    def curricula(self) -> tuple[str, ...]:
        return tuple(c for c in self.cells if c not in PAPER_ARMS)

    @property
    def config(self) -> DictConfig:
        return self.learners[0].config


def load_study(overrides: Sequence[str] = ()) -> Study:
    """The study of conf/experiment/curricula.yaml with ``overrides`` (those its sweeps ran with:
    scale, paths.root, hydra.sweeper.params.seed=3000 for a smaller check; representation=fsr
    for one learner). ConfigError in one line if they do not compose."""
    overrides = [o for o in prepare_overrides(overrides) if not o.startswith("experiment=")]
    if not any(o.startswith("hydra.searchpath") for o in overrides):
        overrides.append(SEARCHPATH)
    named = [o.split("=", 1)[1] for o in overrides if o.startswith("representation=")]
    others = [o for o in overrides if not o.startswith("representation=")]
    parsed = OverridesParser.create().parse_overrides(others)
    fixed = [o.input_line for o in parsed if not o.is_sweep_override()]
    learners, cells, seeds = [], [], set()
    for representation in named or LEARNERS:
        own = [f"experiment={EXPERIMENT}", f"representation={representation}"]
        cfg = compose_config(own + fixed, hydra=True)
        for job in planned_jobs(cfg, own + others):
            values = dict(o.split("=", 1) for o in job)
            if values["cell"] not in cells:
                cells.append(values["cell"])
            seeds.add(int(values["seed"]))
        learners.append(Learner(representation, cfg, Path(cfg.paths.sweep_dir), variant_of(cfg)))
    if not all(arm in cells for arm in PAPER_ARMS):
        raise ValueError(f"conf/experiment/{EXPERIMENT}.yaml must sweep cell over {', '.join(PAPER_ARMS)}: "
                         "the curricula are measured against them")
    return Study(tuple(learners), tuple(cells), tuple(sorted(seeds)))
