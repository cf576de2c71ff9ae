"""The entry point: ``python -m mediated_transfer [overrides]`` runs one learning run; ``-m`` sweeps.

``cli`` checks the command first (sweep.preflight: every job's config, one-line errors, before
any folder exists), then hands it to Hydra. Each job (``main``) runs its learning run unless its
folder already holds the result, writes the result there, logs it to MLflow and prints a
progress line. Folders are deterministic (conf/config.yaml: hydra.run.dir / hydra.sweep.subdir),
so running an interrupted sweep again skips every finished run and computes only the rest.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf

from . import progress, tracking
from .claim import claimed
from .config.compose import CONF_DIR, CONFIG_NAME, ConfigError, first_line, prepare_overrides
from .config.spec import check_same_run, run_spec
from .identity import run_name, run_tags
from .orphan import launcher_watch
from .results import RunResult
from .sweep import preflight

log = logging.getLogger("mediated_transfer")

def run_job(cfg: DictConfig, folder: str | os.PathLike, sweep_dir: str | os.PathLike | None = None,
            variant: str = "") -> dict:
    """Run (or skip) the learning run of ``cfg`` in ``folder``, log it, print a progress line.

    ``sweep_dir``: the sweep's folder when part of a sweep (for the overall count and the time
    left), None for a single run. ``variant``: the run's overrides beyond cell and seed
    (identity.py). Returns a short summary (Hydra's job return value).
    """
    spec = run_spec(cfg)
    folder = Path(folder)
    label = f"{cfg.cell} seed={cfg.seed}" + (f" [{variant}]" if variant else "")
    with claimed(folder) as mine:
        if not mine:
            # Another launch (of this sweep or one that overlaps it) is computing this run.
            log.info("%s: being computed by another process, skipped", label)
            return {"cell": str(cfg.cell), "seed": int(cfg.seed), "variant": variant, "status": "busy",
                    "stale": None, "reward_loss": None, "folder": str(folder)}
        return _run_claimed(cfg, spec, folder, sweep_dir, variant, label)


def _run_claimed(cfg: DictConfig, spec, folder: Path, sweep_dir, variant: str, label: str) -> dict:
    resolved = OmegaConf.to_container(cfg, resolve=True)
    assert isinstance(resolved, dict)
    found = RunResult.read(folder) if RunResult.exists(folder) else None
    stale = None
    if found is not None:
        check_same_run(found, spec, folder)
        stale, result = found.stale(), found
    if found is not None and not (stale and cfg.rerun_stale):
        status = "exists"
        if cfg.tracking.enabled:  # logged from its files, unless MLflow has it already
            tags = run_tags(cfg, folder, spec, variant, str(result.code.get("digest", "")))
            tracking.log_run(_settings(cfg), experiment=str(cfg.name), key=tags["run_key"],
                             run_name=run_name(cfg, variant), result=result,
                             params=tracking.flatten(resolved), tags=tags, artifacts=_artifacts(folder))
    else:
        result = _compute(cfg, spec, folder, resolved, sweep_dir, variant)
        status, stale = "done", None
    sweep_name = f"{cfg.name}/{cfg.scale.name}"
    run = "" if sweep_dir is None else folder.resolve().relative_to(Path(sweep_dir).resolve()).as_posix()
    log.info("%s", progress.run_line(label, result, status, sweep_name,
                                     None if sweep_dir is None else Path(sweep_dir), run, stale))
    return {"cell": str(cfg.cell), "seed": int(cfg.seed), "variant": variant, "status": status,
            "stale": stale, "reward_loss": result.reward_loss, "folder": str(folder)}


def _compute(cfg: DictConfig, spec, folder: Path, resolved: dict, sweep_dir, variant: str) -> RunResult:
    """Run the learning run, followed live in MLflow; write its result into ``folder``."""
    from .provenance import code_version
    from .run import execute_run
    from .saved_learner import forget_learner, save_learner

    _limit_threads(int(cfg.threads_per_run))
    # The folder's learner must be this run's: an older one goes before the run starts.
    forget_learner(folder)
    save = (lambda learner: save_learner(learner, spec, folder)) if cfg.save_learner else None
    every = spec.budget // spec.eval_points
    watch = None if sweep_dir is not None else progress.SingleRunProgress(spec)
    live = None
    if cfg.tracking.enabled:
        tags = run_tags(cfg, folder, spec, variant, code_version(spec.algorithm)["digest"])
        try:
            live = tracking.LiveRun(_settings(cfg), experiment=str(cfg.name), key=tags["run_key"],
                                    run_name=run_name(cfg, variant), params=tracking.flatten(resolved),
                                    tags=tags)
        except Exception as error:  # noqa: BLE001 - the store failed after the sweep's check
            log.warning("%s: not followed in MLflow (%s: %s); rerunning the sweep logs it",
                        folder, type(error).__name__, first_line(error))
    orphaned = launcher_watch()

    def evaluated(step: int, mean_reward: float, success_rate: float) -> None:
        if watch is not None:
            watch.evaluated(step, mean_reward, success_rate)
        if live is not None:
            live.evaluation(step, mean_reward, success_rate)
        if orphaned():
            # The launcher died (e.g. SIGKILL): nobody collects this run; a rerun redoes it.
            raise KeyboardInterrupt("the launching process is gone")

    try:
        with _interrupt_on_sigterm():
            result = execute_run(spec, progress=watch, progress_every=every, on_evaluation=evaluated,
                                 on_finish=save)
        result.config = resolved
        result.write(folder)
    except BaseException as error:
        if live is not None:
            live.end(tracking.stopped_status(error))
        raise
    if live is not None:
        live.finish(result, _artifacts(folder))
    return result


@contextlib.contextmanager
def _interrupt_on_sigterm():
    """SIGTERM as KeyboardInterrupt while a run computes, so its MLflow run ends KILLED (the
    default handler would end the process on the spot). Only the main thread can set it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _settings(cfg: DictConfig) -> tracking.TrackingSettings:
    return tracking.TrackingSettings.from_config(cfg.tracking)


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
    # Hydra's own parser (private, no public one exists), so the command is read exactly as Hydra
    # will read it: a command Hydra would refuse is refused here first, before any work.
    from hydra._internal.utils import get_args_parser

    args = sys.argv[1:] if argv is None else list(argv)
    parsed = get_args_parser().parse_args(args)
    try:
        if parsed.config_name or parsed.config_path or parsed.config_dir:
            raise ConfigError("--config-name/--config-path/--config-dir: this entry point composes "
                              "conf/config.yaml; choose an experiment with experiment=<name>")
        prepared = prepare_overrides(parsed.overrides)
        # --version exits inside the parser; these only print something: nothing to check or prepare.
        informational = (parsed.help or parsed.hydra_help or parsed.cfg or parsed.info
                         or parsed.shell_completion)
        if not informational:
            preflight(parsed.overrides, multirun=parsed.multirun)
    except ConfigError as error:
        raise SystemExit(f"Invalid configuration: {error}") from None
    except Exception as error:  # noqa: BLE001 - store, cache or plan: stop, in one line
        raise SystemExit(f"Could not prepare the runs: {type(error).__name__}: {first_line(error)}") from None
    flags = list(args)
    for override in parsed.overrides:  # the overrides, wherever they stood, replaced by their prepared form
        flags.remove(override)
    sys.argv = [sys.argv[0], *flags, *prepared]
    return main()
