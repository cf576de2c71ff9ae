"""The entry point: ``python -m mediated_transfer [overrides]`` runs one learning run; ``-m`` sweeps.

A composed config (conf/) becomes a RunSpec, the run executes unless its folder already holds
a result, the result is written there and logged to MLflow, and a progress line is printed.
Folders are deterministic (conf/config.yaml: hydra.run.dir / hydra.sweep.subdir), so running
an interrupted sweep again skips every finished run and computes only the rest.

Before a sweep starts, ``Preflight`` checks every distinct job config (a bad combination
fails before any run starts), creates the MLflow store and experiment once, clusters the
source task sets once, and records how many runs the sweep has (for the progress count).
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
import re
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.experimental.callback import Callback
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf

from . import tracking
from .atomic import atomic_write_text
from .results import RunResult

if TYPE_CHECKING:
    from .run import RunSpec

log = logging.getLogger("mediated_transfer")

CONF_DIR = Path(__file__).resolve().parents[2] / "conf"
"""The config tree; it sits next to src/ (the package is installed in editable mode)."""
CONFIG_NAME = "config"
PLAN_FILE = ".sweep_plan.json"
"""Written into the sweep folder before the jobs start: how many runs the sweep has."""


class ConfigError(ValueError):
    """A configuration that cannot run; the message names the key and the allowed values."""


# --- config -> RunSpec ------------------------------------------------------------------------


def spec_values(cfg: Mapping[str, Any]) -> dict[str, Any]:
    """The RunSpec fields of a composed config (DictConfig or its plain-dict form)."""
    algorithm = dict(_plain(cfg["algorithm"]))
    representation = dict(_plain(cfg["representation"]))
    scale = cfg["scale"]
    return {
        "algorithm": algorithm.pop("name"),
        "representation": representation.pop("name"),
        "strategy": cfg["strategy"],
        "n_source": cfg["n_source"],
        "seed": cfg["seed"],
        "budget": scale["budget"],
        "eval_points": scale["eval_points"],
        "eval_episodes": scale["eval_episodes"],
        "threshold": cfg["threshold"],
        "source_pool_size": cfg["source_pool_size"],
        "source_set_seed": cfg["source_set_seed"],
        "cache_dir": cfg["paths"]["cache_dir"],
        "world": dict(_plain(cfg["env"])),
        "algorithm_params": algorithm,
        "representation_params": representation,
    }


def run_spec(cfg: Mapping[str, Any]) -> RunSpec:
    """The validated RunSpec of a composed config; ConfigError before any work if it cannot run."""
    # Imported here: the learners and the environment load only when a run is configured.
    from .run import spec_from_dict

    try:
        values = spec_values(cfg)
        for key in ("n_source", "seed"):
            if isinstance(values[key], bool) or not isinstance(values[key], int):
                raise ValueError(f"{key} must be an integer, got {values[key]!r}")
        return spec_from_dict(values).validate()
    except (ValueError, TypeError) as error:
        raise ConfigError(str(error)) from error


def _plain(node: Any) -> Any:
    return OmegaConf.to_container(node, resolve=True) if isinstance(node, DictConfig) else node


def _comparable(spec: RunSpec) -> dict[str, Any]:
    values = asdict(spec)
    values.pop("cache_dir")  # where sets are cached does not change what a run computes
    return values


# --- one job ----------------------------------------------------------------------------------


def run_job(cfg: DictConfig, folder: str | os.PathLike, sweep_dir: str | os.PathLike | None = None) -> dict:
    """Run (or skip) the learning run of ``cfg`` in ``folder``, log it, print a progress line.

    ``sweep_dir``: the sweep's folder when part of a sweep (for the overall count and the time
    left), None for a single run. Returns a short summary (Hydra's job return value).
    """
    spec = run_spec(cfg)
    folder = Path(folder)
    resolved = OmegaConf.to_container(cfg, resolve=True)
    assert isinstance(resolved, dict)
    if RunResult.exists(folder):
        result = RunResult.read(folder)
        _check_same_run(result, spec, folder)
        status = "exists"
    else:
        from .run import execute_run

        _limit_threads(int(cfg.threads_per_run))
        every = spec.budget // spec.eval_points
        progress = None if sweep_dir is not None else _single_run_progress(spec)
        result = execute_run(spec, progress=progress, progress_every=every)
        result.config = resolved
        result.write(folder)
        status = "done"

    identity = run_identity(cfg, folder, spec)
    if cfg.tracking.enabled:
        settings = tracking.TrackingSettings.from_config(cfg.tracking)
        tracking.log_run(
            settings,
            experiment=str(cfg.name),
            key=identity["run_key"],
            run_name=f"{cfg.cell}/seed={cfg.seed}",
            result=result,
            params=tracking.flatten(resolved),
            tags=identity,
            artifacts=_artifacts(folder),
        )
    log.info("%s", progress_line(cfg, result, status, sweep_dir))
    return {"cell": str(cfg.cell), "seed": int(cfg.seed), "status": status,
            "reward_loss": result.reward_loss, "folder": str(folder)}


def run_identity(cfg: DictConfig, folder: Path, spec: "RunSpec") -> dict[str, str]:
    """MLflow tags of a run: table, cell, sweep, scale, seed and the run key.

    The run key is the run's folder relative to paths.root plus a digest of what the run
    computes: the same run always has the same key, which is how re-running a sweep avoids
    duplicate MLflow runs; another config in the same folder (or another checkout logging to
    the same server with other settings) gets another key.
    """
    root = Path(cfg.paths.root).resolve()
    path = folder.resolve()
    where = path.relative_to(root).as_posix() if path.is_relative_to(root) else path.as_posix()
    return {
        "table": str(cfg.name),
        "cell": str(cfg.cell),
        "sweep": f"{cfg.name}/{cfg.scale.name}",
        "scale": str(cfg.scale.name),
        "seed": str(cfg.seed),
        "strategy": str(cfg.strategy),
        "n_source": str(cfg.n_source),
        "run_key": f"{where}@{spec_digest(spec)}",
    }


def spec_digest(spec: "RunSpec") -> str:
    """Short digest of everything a run computes from (not where it caches)."""
    text = json.dumps(_comparable(spec), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def _check_same_run(result: RunResult, spec: RunSpec, folder: Path) -> None:
    # A folder is named after the cell, the seed and the swept keys; a result computed with
    # other values there (e.g. an override that is not part of the folder name) must not be
    # passed off as this run's.
    if not result.config:
        raise ConfigError(f"{folder / 'result.json'} has no recorded config; delete the folder to rerun it")
    stored = _comparable(run_spec(result.config))
    wanted = _comparable(spec)
    differ = sorted(k for k in wanted if stored.get(k) != wanted[k])
    if differ:
        detail = "; ".join(_difference(k, stored.get(k), wanted[k]) for k in differ)
        raise ConfigError(
            f"{folder} holds a finished run of another configuration ({detail}). Use another "
            "paths.root, or delete the folder to recompute it."
        )


def _difference(key: str, stored: Any, wanted: Any) -> str:
    if isinstance(stored, dict) and isinstance(wanted, dict):
        keys = sorted(k for k in set(stored) | set(wanted) if stored.get(k) != wanted.get(k))
        return ", ".join(f"{key}.{k}: stored {stored.get(k)!r}, now {wanted.get(k)!r}" for k in keys)
    return f"{key}: stored {stored!r}, now {wanted!r}"


def _artifacts(folder: Path) -> list[Path]:
    files = [folder / "result.json", folder / "curve.csv"]
    files += sorted((folder / ".hydra").glob("*.yaml"))
    return [f for f in files if f.is_file()]


def _limit_threads(threads: int) -> None:
    # Sweeps run one job per core: a run that also spreads over all cores only slows the others.
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=threads)
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(threads)


def _single_run_progress(spec: RunSpec):
    started = time.perf_counter()

    def report(step: int, budget: int) -> None:
        elapsed = time.perf_counter() - started
        left = elapsed * (budget - step) / step if step else math.nan
        log.info("%s: step %d/%d, %.0f steps/s, ~%s left", spec.describe(), step, budget,
                 step / elapsed if elapsed > 0 else math.nan, _duration(left))

    return report


# --- progress ---------------------------------------------------------------------------------


def progress_line(cfg: DictConfig, result: RunResult, status: str, sweep_dir) -> str:
    """``[sweep k/n, ~time left] cell seed=s: L_R=..., steps/s`` for a finished (or found) run."""
    what = "found, skipped" if status == "exists" else f"{result.learning_steps_per_s:,.0f} steps/s"
    line = f"{cfg.cell} seed={cfg.seed}: L_R={result.reward_loss:.2f}, {what}"
    if sweep_dir is None:
        return line
    count = sweep_progress(Path(sweep_dir))
    if count is None:
        return f"[{cfg.name}/{cfg.scale.name}] {line}"
    finished, total, left = count
    eta = "" if left is None else f", ~{_duration(left)} left"
    return f"[{cfg.name}/{cfg.scale.name} {finished}/{total}{eta}] {line}"


def sweep_progress(sweep_dir: Path) -> tuple[int, int, float | None] | None:
    """(finished runs, runs of the sweep, estimated seconds left), from the plan file written
    before the sweep started and the result files present; None without a plan."""
    try:
        plan = json.loads((sweep_dir / PLAN_FILE).read_text())
    except (OSError, ValueError):
        return None
    results = [p.stat().st_mtime for p in sweep_dir.glob("**/result.json")]
    finished = min(len(results), plan["total"])
    # Only runs computed since this launch tell the current speed (earlier ones were skipped).
    computed = sum(t >= plan["started"] for t in results)
    elapsed = time.time() - plan["started"]
    left = (plan["total"] - finished) * elapsed / computed if computed else None
    return finished, plan["total"], left


def _duration(seconds: float | None) -> str:
    if seconds is None or not math.isfinite(seconds):
        return "?"
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}h{minutes:02d}m" if hours else f"{minutes}m{secs:02d}s"


# --- before a sweep ---------------------------------------------------------------------------


class Preflight(Callback):
    """Work done once, in the launching process, before anything runs or any folder is made."""

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        try:
            run_spec(config)
        except ConfigError as error:
            raise SystemExit(f"Invalid configuration: {error}") from None

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        try:
            prepare_sweep(config)
        except ConfigError as error:
            raise SystemExit(f"Invalid configuration: {error}") from None


def prepare_sweep(config: DictConfig) -> list[list[str]] | None:
    """Check the sweep's job configs, create the MLflow experiment, warm the source task cache,
    write the plan file. Returns the jobs' override lists (None when the sweeper is not
    Hydra's basic sweeper, whose job list this function cannot reproduce)."""
    jobs = planned_jobs(config)
    # Seeds do not change whether a config is valid: compose one job per distinct rest.
    distinct = {tuple(o for o in job if not o.startswith("seed=")) for job in jobs or [[]]}
    configs = [config] if jobs is None else [_compose(list(job)) for job in sorted(distinct)]
    specs = [run_spec(c) for c in configs]
    names = {str(c.name) for c in configs}
    for c in configs:
        if c.tracking.enabled:
            tracking.prepare(tracking.TrackingSettings.from_config(c.tracking), experiment=str(c.name))
            break
    _warm_source_task_cache(specs)
    sweep_dir = Path(config.hydra.sweep.dir)
    sweep_dir.mkdir(parents=True, exist_ok=True)
    total = None if jobs is None else len(jobs)
    if total is not None:
        atomic_write_text(sweep_dir / PLAN_FILE, json.dumps({"total": total, "started": time.time()}) + "\n")
    log.info("sweep %s: %s runs in %s", ", ".join(sorted(names)), total or "?", sweep_dir)
    return jobs


def planned_jobs(config: DictConfig) -> list[list[str]] | None:
    """The override list of every job, exactly as Hydra's basic sweeper will build them."""
    # Private Hydra API (pinned to 1.3): the sweeper's own expansion, so the plan cannot drift.
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
    from hydra.core.override_parser.overrides_parser import OverridesParser

    if not str(config.hydra.sweeper.get("_target_", "")).endswith("BasicSweeper"):
        return None
    params = config.hydra.sweeper.get("params") or {}
    lines = [f"{k}={v}" for k, v in params.items()] + list(config.hydra.overrides.task)
    overrides = OverridesParser.create().parse_overrides(lines)
    return [list(job) for batch in BasicSweeper.split_arguments(overrides, None) for job in batch]


def _compose(overrides: list[str]) -> DictConfig:
    from hydra import compose

    return compose(CONFIG_NAME, overrides=overrides)


def _warm_source_task_cache(specs: Sequence[RunSpec]) -> None:
    from .transfer.source_tasks import precompute_source_task_sets

    groups: dict[tuple, set[int]] = {}
    for s in specs:
        if s.cache_dir is not None:
            groups.setdefault((s.world, s.source_pool_size, s.source_set_seed, s.cache_dir), set()).add(s.n_source)
    for (world, pool_size, seed, cache_dir), n_sources in groups.items():
        if n_sources - {0}:
            precompute_source_task_sets(n_sources, world, pool_size, seed, cache_dir=cache_dir)


# --- command line -----------------------------------------------------------------------------


def numeric_groups(conf_dir: Path = CONF_DIR) -> set[str]:
    """Config groups whose options are all named by numbers (n_source)."""
    groups = set()
    for group in conf_dir.iterdir():
        names = [p.stem for p in group.glob("*.yaml")] if group.is_dir() else []
        if names and all(n.isdigit() for n in names):
            groups.add(group.name)
    return groups


def quote_numeric_choices(args: Sequence[str], groups: set[str] | None = None) -> list[str]:
    """``n_source=15`` -> ``n_source='15'`` (and ``n_source=1,15`` -> ``n_source='1','15'``).

    Hydra reads an unquoted 15 as the integer 15 and rejects it as a group choice, whose
    options are names; quoting keeps the natural spelling usable on the command line.
    """
    groups = numeric_groups() if groups is None else groups
    out = []
    for arg in args:
        match = re.fullmatch(r"([\w.]+)=(\d+(?:,\d+)*)", arg)
        if match and match.group(1) in groups:
            arg = f"{match.group(1)}=" + ",".join(f"'{n}'" for n in match.group(2).split(","))
        out.append(arg)
    return out


@hydra.main(config_path=str(CONF_DIR), config_name=CONFIG_NAME, version_base="1.3")
def main(cfg: DictConfig) -> dict:
    hydra_cfg = HydraConfig.get()
    sweep_dir = hydra_cfg.sweep.dir if hydra_cfg.mode == RunMode.MULTIRUN else None
    try:
        return run_job(cfg, hydra_cfg.runtime.output_dir, sweep_dir)
    except ConfigError as error:
        if sweep_dir is not None:
            raise  # in a worker: let the launcher report it with the job
        raise SystemExit(f"Invalid configuration: {error}") from None


def cli(argv: Sequence[str] | None = None) -> Any:
    """``python -m mediated_transfer``: Hydra's command line, with numeric group choices quoted."""
    args = sys.argv[1:] if argv is None else list(argv)
    sys.argv = [sys.argv[0], *quote_numeric_choices(args)]
    return main()
