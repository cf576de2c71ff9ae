"""The sweep machinery: what runs around each learning run of a command (app.py, the entry point,
calls it), none of it part of what a run computes.

This module checks every run of a command before anything runs and prepares what runs share;
beside it: ``claim`` (one process at a time per run folder), ``orphan`` (a worker whose
launcher was killed stops), ``identity`` (a run's variant, MLflow name, tags and run key),
``progress`` (progress lines, time left) and ``tracking`` (MLflow logging).

``preflight`` is called by the entry point before Hydra starts, in the launching process, so a
bad config stops the command before any folder exists, and its errors are never turned into
warnings (Hydra's callbacks would do that). For a sweep it composes every distinct job config
(seeds do not change validity) and checks it, then creates the MLflow store and experiment once
(SQLite must not be initialised by parallel workers), clusters the source task sets once, and
writes the plan that progress lines count against. It returns the command's runs, which the
entry point settles if the command is stopped (``interrupted``).
"""

from __future__ import annotations

import itertools
import logging
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf

from ..config.compose import ConfigError, compose_config, prepare_overrides
from ..config.spec import run_spec
from ..provenance.judge import judge
from . import answered
from .identity import run_where
from .progress import PLAN_PREFIX, write_plan  # noqa: F401 - the plans' writer, for the launchers and tests

if TYPE_CHECKING:
    from ..run import RunSpec
    from .interrupted import PlannedRun

log = logging.getLogger("mediated_transfer")

def preflight(overrides: Sequence[str], multirun: bool) -> "Prepared":
    """Check the command's config(s) and prepare a sweep; ConfigError (one line) if anything is
    wrong. Returns the command's runs (one for a single run), answered if every run of a sweep
    is finished and logged already."""
    overrides = prepare_overrides(overrides)  # also refuses an override Hydra cannot parse
    parsed = OverridesParser.create().parse_overrides(list(overrides))
    fixed = [o.input_line for o in parsed if not o.is_sweep_override()]
    base = compose_config(fixed, hydra=True)
    _check_tuned(base)
    if not multirun and base.hydra.mode != RunMode.MULTIRUN:
        if len(fixed) < len(overrides):
            swept = [o.input_line for o in parsed if o.is_sweep_override()]
            raise ConfigError(f"{' '.join(swept)} sweeps over values: add -m (--multirun)")
        _try_plugins(run_spec(base))
        _prepare_tracking(base)  # a store that cannot be reached stops the run now, in one line
        return Prepared([_planned(base, Path(base.hydra.run.dir), base)])
    # Hydra's own overrides (launcher, ...) are not part of a job's config.
    jobs = planned_jobs(base, [o for o in overrides if not _is_hydra_override(o)])
    distinct = sorted({_without_seed(job) for job in jobs})
    # Where a user's plugins live counts for every job (hydra.searchpath is Hydra's own key).
    searchpath = [o for o in overrides if o.lstrip("+").startswith("hydra.searchpath")]
    # A job whose overrides are the command's own (no sweep besides seeds) is the base config.
    configs = {job: base if set(job) | set(searchpath) == set(fixed) else
               compose_config(list(job) + searchpath, hydra=True) for job in distinct}
    specs = {job: run_spec(cfg) for job, cfg in configs.items()}
    plans: dict[Path, list[str]] = {}
    recompute: dict[Path, list[str]] = {}
    planned, found = [], []
    for job in jobs:
        cfg = _with_seed(configs[_without_seed(job)], job)
        sweep_dir, run = Path(cfg.hydra.sweep.dir), str(cfg.hydra.sweep.subdir).rstrip("/")
        # A finished run of another configuration in a job's folder stops the sweep now, not
        # as a traceback halfway through it (the judge raises ConfigError). A damaged run is
        # set aside by its job (under the run's claim: another launch may be writing it right
        # now), saying why; like a stale run recomputed, it is not finished till then.
        folder = sweep_dir / run
        spec = replace(specs[_without_seed(job)], seed=int(cfg.seed))
        verdict = judge(folder, spec, rerun_stale=bool(cfg.rerun_stale))
        if verdict.found and not verdict.kept:
            recompute.setdefault(sweep_dir, []).append(run)
        plans.setdefault(sweep_dir, []).append(run)
        planned.append(_planned(cfg, folder, base))
        found.append(answered.Found(cfg, spec, folder, str(cfg.hydra.job.override_dirname), verdict))
    with answered.answerable(base, found) as finished:
        if finished:
            _write_plans(base, plans, recompute)
            answered.answer(found)
            return Prepared(planned, answered=True)
    _prepare_tracking(base)
    _warm_source_task_cache(list(specs.values()))
    for spec in specs.values():
        _try_plugins(spec)
    _write_plans(base, plans, recompute)
    return Prepared(planned)


@dataclass(frozen=True)
class Prepared:
    """A checked command: its runs, and whether preflight answered it (every run finished and
    logged: sweep/answered.py), so that nothing is left to launch."""

    runs: list["PlannedRun"]
    answered: bool = False


def _write_plans(base: DictConfig, plans: dict[Path, list[str]], recompute: dict[Path, list[str]]) -> None:
    for sweep_dir, runs in plans.items():
        write_plan(sweep_dir, runs, recompute.get(sweep_dir, []))
        log.info("sweep %s: %d runs in %s", base.name, len(runs), sweep_dir)


def _planned(cfg: DictConfig, folder: Path, command: DictConfig) -> "PlannedRun":
    from .interrupted import PlannedRun  # not at the top: see _prepare_tracking
    from .tracking import TrackingSettings

    # A SLURM job goes on when its launcher stops: its live MLflow run is not the launcher's to
    # end. (The launcher is the command's: a job's config leaves Hydra's overrides out.)
    elsewhere = "slurm" in str(OmegaConf.select(command, "hydra.launcher._target_", default="")).lower()
    settings = TrackingSettings.from_config(cfg.tracking) if cfg.tracking.enabled and not elsewhere else None
    return PlannedRun(folder, run_where(cfg.paths.root, folder), str(cfg.name), settings)


def _without_seed(job: Sequence[str]) -> tuple[str, ...]:
    # Seeds do not change whether a config is valid: one composition per distinct rest.
    return tuple(o for o in job if not o.startswith("seed="))


def _with_seed(cfg: DictConfig, job: Sequence[str]) -> DictConfig:
    seed = next((o.split("=", 1)[1] for o in job if o.startswith("seed=")), None)
    if seed is None:
        return cfg
    cfg = cfg.copy()
    OmegaConf.update(cfg, "seed", int(seed))
    return cfg


def planned_jobs(config: DictConfig, overrides: Sequence[str] | None = None) -> list[list[str]]:
    """The override list of every job, as Hydra's basic sweeper builds them: the config's
    ``hydra.sweeper.params`` first, then the command line's overrides (default: the config's
    own), a later value of a key replacing an earlier one in its place; every combination."""
    params = config.hydra.sweeper.get("params") or {}
    task = list(config.hydra.overrides.task) if overrides is None else list(overrides)
    lines = [f"{k}={v}" for k, v in params.items()] + task
    choices: OrderedDict[str, list[str]] = OrderedDict()
    for override in OverridesParser.create().parse_overrides(lines):
        key = override.get_key_element()
        if not override.is_sweep_override():
            choices[key] = [f"{key}={override.get_value_element_as_str()}"]
        elif override.is_discrete_sweep():
            choices[key] = [f"{key}={value}" for value in override.sweep_string_iterator()]
        else:
            raise ConfigError(f"{override.input_line}: interval sweeps need a sweeper plugin (e.g. tuning)")
    return [list(job) for job in itertools.product(*choices.values())]


def _is_hydra_override(override: str) -> bool:
    return override.lstrip("+~").startswith(("hydra.", "hydra/"))


def _prepare_tracking(config: DictConfig) -> None:
    # Imported here, not at the top: `python -m mediated_transfer.sweep.tracking` (make mlflow-ui)
    # imports this package first, and must not find its module imported already.
    from . import tracking

    if config.tracking.enabled:
        try:
            tracking.prepare(tracking.TrackingSettings.from_config(config.tracking), experiment=str(config.name))
        except ValueError as error:
            raise ConfigError(str(error)) from None


def _check_tuned(config: DictConfig) -> None:
    """ConfigError (one line) if the command requires Table I's tuned values (``require_tuned``)
    and its learner has none: an experiment registered on tuned values never runs without."""
    if not OmegaConf.select(config, "require_tuned", default=False):
        return
    from ..config.compose import source_dirs
    from ..config.tuned import tuned_line

    runtime = config.hydra.runtime
    line = tuned_line(runtime.choices, source_dirs(runtime.config_sources))
    if line.startswith("tuned: none"):
        raise ConfigError(f"require_tuned=true ({config.name}): {line.removeprefix('tuned: ')}; tune the learner "
                          "first (Table I's protocol, docs/tuning.md), or require_tuned=false to run it on its provisional values")


def _try_plugins(spec: "RunSpec") -> None:
    """Build a run's plugins once (a strategy, learner or representation from outside the
    package), so that a value they refuse stops the command now, in one line naming it."""
    from .. import plugins
    from ..learners.factory import learner_target, make_learner
    from ..recorder import RunStreams

    foreign = {"strategy": spec.strategy_class(), "algorithm": learner_target(spec.algorithm, spec.algorithm_target)}
    foreign = {k: t for k, t in foreign.items() if not plugins.path_of(t).startswith("mediated_transfer.")}
    if not foreign:
        return
    try:
        if "strategy" in foreign:
            RunStreams.of(spec)
        if "algorithm" in foreign:
            make_learner(spec.algorithm, spec.representation, spec.algorithm_params, spec.representation_params,
                         world=spec.make_world(), algorithm_target=spec.algorithm_target,
                         representation_target_path=spec.representation_target)
    except (ValueError, TypeError) as error:
        raise ConfigError(str(error).strip().splitlines()[0]) from None


def _warm_source_task_cache(specs: Sequence["RunSpec"]) -> None:
    from ..transfer.source_tasks import precompute_source_task_sets

    groups: dict[tuple, set[int]] = {}
    for s in specs:
        if s.cache_dir is not None:
            groups.setdefault((s.make_world(), s.source_pool_size, s.source_set_seed, s.cache_dir),
                              set()).add(s.n_source)
    for (world, pool_size, seed, cache_dir), n_sources in groups.items():
        if n_sources - {0}:
            precompute_source_task_sets(n_sources, world, pool_size, seed, cache_dir=cache_dir)
