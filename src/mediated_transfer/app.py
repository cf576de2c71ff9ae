"""The entry point: ``python -m mediated_transfer [overrides]`` runs one learning run; ``-m`` sweeps.

``cli`` checks the command first (sweep.preflight: every job's config, one-line errors, before
any folder exists), then hands it to Hydra. Each job (``main``) runs its learning run unless its
folder already holds the result, writes the result there, logs it to MLflow and prints a
progress line. Folders are deterministic (conf/config.yaml: hydra.run.dir / hydra.sweep.subdir),
so running an interrupted sweep again skips every finished run and computes only the rest.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf

from . import progress, tracking
from .config.compose import CONF_DIR, CONFIG_NAME, ConfigError, is_override, prepare_overrides
from .config.spec import comparable, run_spec
from .identity import run_name, run_tags
from .results import RunResult
from .sweep import preflight

log = logging.getLogger("mediated_transfer")

INFORMATIONAL_FLAGS = ("-h", "--help", "--hydra-help", "-c", "--cfg", "-i", "--info", "--version", "--shell-completion")
"""Flags that only print something: no checks, no preparation."""


def run_job(cfg: DictConfig, folder: str | os.PathLike, sweep_dir: str | os.PathLike | None = None,
            variant: str = "") -> dict:
    """Run (or skip) the learning run of ``cfg`` in ``folder``, log it, print a progress line.

    ``sweep_dir``: the sweep's folder when part of a sweep (for the overall count and the time
    left), None for a single run. ``variant``: the run's overrides beyond cell and seed
    (identity.py). Returns a short summary (Hydra's job return value).
    """
    spec = run_spec(cfg)
    folder = Path(folder)
    resolved = OmegaConf.to_container(cfg, resolve=True)
    assert isinstance(resolved, dict)
    stale = None
    if RunResult.exists(folder):
        result = RunResult.read(folder)
        _check_same_run(result, spec, folder)
        stale = result.stale()
    if RunResult.exists(folder) and not (stale and cfg.rerun_stale):
        status = "exists"
    else:
        from .run import execute_run

        _limit_threads(int(cfg.threads_per_run))
        every = spec.budget // spec.eval_points
        report = None if sweep_dir is not None else progress.single_run_progress(spec)
        result = execute_run(spec, progress=report, progress_every=every)
        result.config = resolved
        result.write(folder)
        status, stale = "done", None

    if cfg.tracking.enabled:
        settings = tracking.TrackingSettings.from_config(cfg.tracking)
        tags = run_tags(cfg, folder, spec, variant, str(result.code.get("digest", "")))
        tracking.log_run(
            settings,
            experiment=str(cfg.name),
            key=tags["run_key"],
            run_name=run_name(cfg, variant),
            result=result,
            params=tracking.flatten(resolved),
            tags=tags,
            artifacts=_artifacts(folder),
        )
    label = f"{cfg.cell} seed={cfg.seed}" + (f" [{variant}]" if variant else "")
    sweep_name = f"{cfg.name}/{cfg.scale.name}"
    log.info("%s", progress.run_line(label, result, status, sweep_name,
                                     None if sweep_dir is None else Path(sweep_dir), stale))
    return {"cell": str(cfg.cell), "seed": int(cfg.seed), "variant": variant, "status": status,
            "stale": stale, "reward_loss": result.reward_loss, "folder": str(folder)}


def _check_same_run(result: RunResult, spec, folder: Path) -> None:
    # A folder is named after the cell, the seed and the swept keys; a result computed with
    # other values there (e.g. an override excluded from the folder name) must not be passed
    # off as this run's.
    if not result.config:
        raise ConfigError(f"{folder / 'result.json'} has no recorded config; delete the folder to rerun it")
    stored = comparable(run_spec(result.config))
    wanted = comparable(spec)
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


@hydra.main(config_path=str(CONF_DIR), config_name=CONFIG_NAME, version_base="1.3")
def main(cfg: DictConfig) -> dict:
    hydra_cfg = HydraConfig.get()
    sweep_dir = hydra_cfg.sweep.dir if hydra_cfg.mode == RunMode.MULTIRUN else None
    variant = str(hydra_cfg.job.override_dirname)
    try:
        return run_job(cfg, hydra_cfg.runtime.output_dir, sweep_dir, variant)
    except ConfigError as error:
        if sweep_dir is not None:
            raise  # in a worker: let the launcher report it with the job
        raise SystemExit(f"Invalid configuration: {error}") from None


def cli(argv: Sequence[str] | None = None) -> Any:
    """``python -m mediated_transfer``: check the command, then Hydra's command line."""
    args = sys.argv[1:] if argv is None else list(argv)
    overrides = [a for a in args if is_override(a)]
    try:
        quoted = iter(prepare_overrides(overrides))
        if not any(a in INFORMATIONAL_FLAGS or a.startswith("--cfg=") for a in args):
            preflight(overrides, multirun=any(a in ("-m", "--multirun") for a in args))
    except ConfigError as error:
        raise SystemExit(f"Invalid configuration: {error}") from None
    except Exception as error:  # noqa: BLE001 - store, cache or plan: stop, in one line
        raise SystemExit(f"Could not prepare the runs: {type(error).__name__}: {_first_line(error)}") from None
    sys.argv = [sys.argv[0], *(next(quoted) if is_override(a) else a for a in args)]
    return main()


def _first_line(error: BaseException) -> str:
    lines = str(error).strip().splitlines()
    return lines[0] if lines else ""
