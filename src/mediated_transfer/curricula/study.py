"""A curricula study as its experiment file defines it: its groups (a learner in a world), arms,
seeds and run folders. The current study is issue 42's (conf/experiment/curricula2.yaml); the
first one (conf/experiment/curricula.yaml, issue 35) is read for its superseded section."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple
from pathlib import Path

from omegaconf import DictConfig

from hydra.core.override_parser.overrides_parser import OverridesParser

from ..config.compose import CONF_DIR, compose_config, prepare_overrides
from ..reporting.collect import collect_sweep
from ..reporting.compose import variant_of
from ..sweep import planned_jobs

EXPERIMENT = "curricula2"
FIRST_EXPERIMENT = "curricula"
DQN_EXPERIMENT = "curricula2_dqn"
SEARCHPATH = "hydra.searchpath=[pkg://auto_curricula.conf]"
"""Where the curricula's options live (a plugin's config folder, as a user's would)."""
NONE, REGULAR, SCAFFOLDED = "none_0", "regular_100", "scaffolded_100"
PAPER_ARMS = (NONE, REGULAR, SCAFFOLDED)
"""The paper's arms; every other arm of the sweep is an automatic curriculum."""
HANDOVER_ARMS = ("plr_handover_100", "learnability_handover_100")
"""Q2's arms: feedback curricula as orderings of C under the paper's hand-over rule."""
DEFAULT_WORLD = "default"


@dataclass(frozen=True)
class Group:
    """One learner in one world: a column of the study."""

    representation: str
    world: str
    config: DictConfig
    """The composed experiment for this group (scale, paths, threshold, Hydra's part)."""
    sweep_dir: Path
    variant: str
    """The runs' folder below seed=<k>/ (Hydra's override_dirname: env=<w>,representation=<r>)."""

    @property
    def name(self) -> str:
        return f"{self.representation.upper()}, {self.world}"


@dataclass(frozen=True)
class Study:
    experiment: str
    groups: tuple[Group, ...]
    cells: tuple[str, ...]
    seeds: tuple[int, ...]

    @property
    def curricula(self) -> tuple[str, ...]:
        """Q1's arms: the automatic curricula in their own setting."""
        return tuple(c for c in self.cells if c not in PAPER_ARMS + HANDOVER_ARMS)

    @property
    def handovers(self) -> tuple[str, ...]:
        return tuple(c for c in self.cells if c in HANDOVER_ARMS)

    @property
    def config(self) -> DictConfig:
        return self.groups[0].config

    @property
    def registration(self) -> Path:
        """Its experiment file: questions, arms, seeds, measures and rules, committed before its runs."""
        return CONF_DIR / "experiment" / f"{self.experiment}.yaml"


Collected = tuple[dict[str, dict[str, list]], dict[str, dict[str, int]]]
"""group -> arm -> its finished runs, and group -> arm -> its failed runs' count."""


class StudyRuns(NamedTuple):
    """What the report reads: the linear groups', the DQN's and the first study's runs."""

    linear: Collected
    dqn: Collected
    first: Collected

    def results(self):
        return [r for runs, _ in self for arms in runs.values() for arm in arms.values() for r in arm]


def load_study(overrides: Sequence[str] = (), experiment: str = EXPERIMENT,
               references: tuple[str, ...] = PAPER_ARMS) -> Study:
    """The study of conf/experiment/<experiment>.yaml with ``overrides`` (those its sweep ran with:
    scale, paths.root, hydra.sweeper.params.seed=4000 for a smaller check, representation=fsr or
    env=default for one group). ConfigError in one line if they do not compose."""
    overrides = [o for o in prepare_overrides(overrides) if not o.startswith("experiment=")]
    if not any(o.startswith("hydra.searchpath") for o in overrides):
        overrides.append(SEARCHPATH)
    own = [f"experiment={experiment}"]
    parsed = OverridesParser.create().parse_overrides(overrides)
    fixed = [o.input_line for o in parsed if not o.is_sweep_override()
             and o.get_key_element() not in ("env", "representation")]
    jobs = [dict(o.split("=", 1) for o in job) for job in planned_jobs(compose_config(own + fixed, hydra=True),
                                                                          own + overrides)]
    cells = list(dict.fromkeys(job["cell"] for job in jobs))
    pairs = dict.fromkeys((job.get("representation"), job.get("env")) for job in jobs)
    groups = []
    for representation, world in pairs:
        named = [f"{key}={value}" for key, value in (("env", world), ("representation", representation)) if value]
        cfg = compose_config(own + fixed + named, hydra=True)
        groups.append(Group(str(cfg.representation.name), world or DEFAULT_WORLD, cfg,
                            Path(cfg.paths.sweep_dir), variant_of(cfg)))
    if not all(arm in cells for arm in references):
        raise ValueError(f"conf/experiment/{experiment}.yaml must sweep cell over {', '.join(references)}: "
                         "the curricula are measured against them")
    return Study(experiment, tuple(groups), tuple(cells), tuple(sorted({int(job["seed"]) for job in jobs})))


def load_first_study(overrides: Sequence[str] = ()) -> Study:
    """The first study (issue 35): one sweep per learner, swept by representation= on the command
    line, so each learner is composed on its own."""
    kept = [o for o in prepare_overrides(overrides) if o.startswith(("scale=", "paths.", "tracking="))]
    studies = [load_study([*kept, f"representation={r}"], FIRST_EXPERIMENT) for r in ("rbf", "fsr")]
    return Study(FIRST_EXPERIMENT, tuple(g for s in studies for g in s.groups), studies[0].cells, studies[0].seeds)


def collect(study: Study) -> tuple[dict[str, dict[str, list]], dict[str, dict[str, int]]]:
    """group -> arm -> its finished runs (registered seeds only), and the failed ones' counts."""
    runs, failed = {}, {}
    for group in study.groups:
        cfg = group.config
        cells = collect_sweep(group.sweep_dir, str(cfg.algorithm.name), group.representation,
                              int(cfg.scale.budget), int(cfg.scale.eval_points), group.variant,
                              int(cfg.scale.eval_episodes))
        runs[group.name] = {c: [r for r in cells[c].results if r.seed in study.seeds] if c in cells else []
                            for c in study.cells}
        failed[group.name] = {c: len(cells[c].failed) if c in cells else 0 for c in study.cells}
    return runs, failed
