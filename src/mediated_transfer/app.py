"""The entry point: ``python -m mediated_transfer [overrides]`` runs one learning run; ``-m`` sweeps.

``cli`` checks the command first (sweep.preflight: every job's config, one-line errors, before
any folder exists), then hands it to Hydra. Each job (``main``) is sweep/job.py's ``run_job``:
reuse or compute the run, write it, log it, print its progress line. A command stopped by Ctrl-C,
SIGTERM or a dead worker ends its runs' MLflow runs and says so in one line (sweep/interrupted.py);
a full disk or a damaged MLflow store stops it in one line too (sweep/faults.py).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import sys
from collections.abc import Sequence
from typing import Any

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig

from .config.compose import CONF_DIR, CONFIG_NAME, ConfigError, first_line, prepare_overrides
from .config.help import app_help
from .sweep import faults, interrupted, preflight
from .sweep.job import run_job, run_jobs  # noqa: F401 - the launchers' and tests' door


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
    except faults.Fault as error:
        if multiprocessing.parent_process() is not None:
            raise  # in a pool's worker: its launcher says it once the other jobs have ended
        raise SystemExit(str(error)) from None


def cli(argv: Sequence[str] | None = None) -> Any:
    """``python -m mediated_transfer``: check the command, then Hydra's command line."""
    # Hydra's own parser (private, no public one exists), so the command is read exactly as Hydra
    # will read it: a command Hydra would refuse is refused here first, before any work.
    from hydra._internal.utils import get_args_parser

    args = sys.argv[1:] if argv is None else list(argv)
    # Intermixed: `experiment=x -m cell=...` as documented (flags among the overrides); Hydra
    # then reads the flags first (sys.argv is rebuilt below).
    parsed = get_args_parser().parse_intermixed_args(args)
    runs: list = []
    try:
        with interrupted.sigterm_interrupts():
            return _cli(args, parsed, runs)
    except (KeyboardInterrupt, interrupted.WorkerLost) as error:
        # Ctrl-C, SIGTERM or a dead worker: the runs its workers left RUNNING end, one line.
        with contextlib.suppress(KeyboardInterrupt):  # a second Ctrl-C: stop settling, quietly
            interrupted.settle(runs)
        line, status = interrupted.exit_line(runs, error)
        print(line, file=sys.stderr)
        raise SystemExit(status) from None
    except BaseException:  # a run's error (Hydra printed it): the runs its pool killed end too
        with contextlib.suppress(Exception, KeyboardInterrupt):
            interrupted.settle(runs)
        raise


def _cli(args: list[str], parsed, runs: list) -> Any:
    try:
        modes = [flag for flag, given in (("-m/--multirun", parsed.multirun), ("--cfg", parsed.cfg),
                                          ("--info", parsed.info), ("--run", parsed.run),
                                          ("--shell-completion", parsed.shell_completion)) if given]
        if len(modes) > 1:  # Hydra refuses them together, with a traceback
            raise ConfigError(f"{' and '.join(modes)} cannot be combined (Hydra runs one mode); "
                              "e.g. --cfg job without -m prints the config of one job")
        if parsed.config_name or parsed.config_path or parsed.config_dir:
            raise ConfigError("--config-name/--config-path/--config-dir: this entry point composes "
                              "conf/config.yaml; choose an experiment with experiment=<name>")
        prepared = prepare_overrides(parsed.overrides)  # also checks a hydra.searchpath
        if parsed.help:  # Hydra's help, with the search path's options (config/help.py)
            return app_help(parsed, prepared)
        # --version exits inside the parser; these only print something: nothing to check or prepare.
        informational = (parsed.help or parsed.hydra_help or parsed.cfg or parsed.info
                         or parsed.shell_completion)
        if not informational:
            prepared_runs = preflight(parsed.overrides, multirun=parsed.multirun)
            runs += prepared_runs.runs
            if prepared_runs.answered:  # every run finished and logged: nothing to launch
                return None
    except ConfigError as error:
        raise SystemExit(f"Invalid configuration: {error}") from None
    except Exception as error:  # noqa: BLE001 - store, cache or plan: stop, in one line
        fault = error if isinstance(error, faults.Fault) else faults.disk_full(error)
        what = str(fault) if fault is not None else f"{type(error).__name__}: {first_line(error)}"
        raise SystemExit(f"Could not prepare the runs: {what}") from None
    flags = list(args)
    for override in parsed.overrides:  # the overrides, wherever they stood, replaced by their prepared form
        flags.remove(override)
    sys.argv = [sys.argv[0], *flags, *prepared]
    return main()
