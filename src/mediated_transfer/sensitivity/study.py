"""The sensitivity study as its experiment file defines it: worlds, arms, seeds, run folders."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from hydra.core.override_parser.overrides_parser import OverridesParser

from ..config.compose import compose_config, prepare_overrides
from ..env.config import WorldConfig
from ..env.door import world_config
from ..reporting.compose import variant_of
from ..sweep import planned_jobs

EXPERIMENT = "sensitivity"
BASELINE_WORLD = "default"
"""Today's world: every other world changes one reading of it."""


@dataclass(frozen=True)
class World:
    """One world of the study: a conf/env/ option."""

    option: str
    config: WorldConfig
    variant: str
    """The runs' Hydra override_dirname (env=<option>): the folder below each cell/seed."""

    def changes(self, baseline: WorldConfig) -> str:
        """What this world changes in ``baseline``, e.g. 'goal_radius 2 -> 1'."""
        mine, theirs = self.config.to_dict(), baseline.to_dict()
        changed = [f"{key} {theirs[key]:g} -> {value:g}" if isinstance(value, float)
                   else f"{key} {theirs[key]} -> {value}"
                   for key, value in mine.items() if value != theirs[key]]
        return ", ".join(changed) or "today's world"


@dataclass(frozen=True)
class Study:
    config: DictConfig
    """The composed experiment (scale, paths, learner, threshold)."""
    worlds: tuple[World, ...]
    cells: tuple[str, ...]
    """The arms: none_0 first, then the transfer arms."""
    seeds: tuple[int, ...]
    sweep_dir: Path
    variant: str = ""
    """The learner's overrides beyond the study's own worlds, arms and seeds (e.g.
    tuned=linear_q_rbf_round1): '' for the study as pre-registered."""

    @property
    def baseline(self) -> World:
        return next(w for w in self.worlds if w.option == BASELINE_WORLD)

    @property
    def transfer_cells(self) -> tuple[str, ...]:
        return tuple(c for c in self.cells if c != "none_0")


def load_study(overrides: Sequence[str] = ()) -> Study:
    """The study of conf/experiment/sensitivity.yaml with ``overrides`` (those the sweep ran
    with: scale, paths.root, ...). ConfigError in one line if they do not compose."""
    overrides = [o for o in prepare_overrides(overrides) if not o.startswith("experiment=")]
    # A sweep override (env=default,tool_frame: a smaller check) narrows the study's own list.
    parsed = OverridesParser.create().parse_overrides(overrides)
    fixed = [o.input_line for o in parsed if not o.is_sweep_override()]
    # A world named alone (env=default) narrows the study's worlds; each world is composed below.
    learner = [o for o in fixed if o.split("=", 1)[0].lstrip("+~") != "env"]
    base = compose_config([f"experiment={EXPERIMENT}", *learner], hydra=True)
    jobs = planned_jobs(base, [f"experiment={EXPERIMENT}", *overrides])
    values: dict[str, list[str]] = {"env": [], "cell": [], "seed": []}
    for job in jobs:
        for override in job:
            key, _, value = override.partition("=")
            if key in values and value not in values[key]:
                values[key].append(value)
    if "none_0" not in values["cell"] or BASELINE_WORLD not in values["env"]:
        raise ValueError(f"conf/experiment/{EXPERIMENT}.yaml must sweep env over {BASELINE_WORLD} "
                         f"and cell over none_0: the gains are measured against both")
    worlds = []
    for option in values["env"]:
        cfg = compose_config([f"experiment={EXPERIMENT}", *learner, f"env={option}"], hydra=True)
        node = OmegaConf.to_container(cfg.env, resolve=True)
        world = world_config(node.pop("_target_", None), node)
        worlds.append(World(option, world, variant_of(cfg)))
    cells = ["none_0"] + [c for c in values["cell"] if c != "none_0"]
    return Study(base, tuple(worlds), tuple(cells), tuple(sorted(int(s) for s in values["seed"])),
                 Path(base.paths.sweep_dir), variant_of(base))
