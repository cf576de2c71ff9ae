"""The config an experiment's sweep ran with, composed again for its report, and the variant
it names. Composing (and its one-line errors) is config.compose's, shared with the entry point,
so a report accepts exactly the overrides its sweep accepted.
"""

from __future__ import annotations

from collections.abc import Sequence

from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from ..config.compose import CONF_DIR, ConfigError, compose_config, first_line
from .collect import BASELINE


class ReportError(Exception):
    """A report that cannot be built as asked; the message is one line saying why and what to do."""


def experiment_names() -> list[str]:
    return sorted(p.stem for p in (CONF_DIR / "experiment").glob("*.yaml"))


def split_experiments(overrides: Sequence[str]) -> tuple[list[str], list[str]]:
    """(the experiments named by ``experiment=a,b``, the other overrides)."""
    names, rest = [], []
    for arg in overrides:
        if arg.startswith("experiment="):
            names += [n for n in arg.split("=", 1)[1].split(",") if n]
        else:
            rest.append(arg)
    allowed = experiment_names()
    unknown = [n for n in names if n not in allowed]
    if unknown:
        raise ReportError(f"experiment={','.join(unknown)}: no such experiment; allowed: {', '.join(allowed)}")
    return names, rest


def compose_experiment(name: str, overrides: Sequence[str]) -> DictConfig:
    """The config of experiment ``name`` with ``overrides``, Hydra's part included: its
    hydra.job.override_dirname is the variant, as it was for the sweep's runs."""
    try:
        return compose_config([f"experiment={name}", *overrides], hydra=True)
    except ConfigError as error:
        raise ReportError(str(error)) from None


def variant_of(cfg: DictConfig) -> str:
    """The variant ``cfg`` describes; the baseline for a config composed without Hydra's part."""
    return str(OmegaConf.select(cfg, "hydra.job.override_dirname", default=BASELINE))


def one_line(error: BaseException) -> str:
    """``error`` as one line: its key, if it names one, and the first line of its message."""
    if isinstance(error, OmegaConfBaseException) and error.full_key:
        return f"{error.full_key}: {first_line(error.msg or str(error))}"
    return first_line(str(error)) or type(error).__name__


USER_ERRORS = (ReportError, ConfigError, OmegaConfBaseException, OSError, ValueError)
"""What a reporting command reports as one line: mistakes in the command or missing runs.
Anything else is a bug and keeps its traceback."""
