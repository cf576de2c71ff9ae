"""The config an experiment's sweep ran with, composed again for its report, and the variant
it names; Hydra's and OmegaConf's errors turned into one line that names the key and the allowed
values (the user mistyped something; a traceback would not help).
"""

from __future__ import annotations

from collections.abc import Sequence

from hydra.errors import HydraException, MissingConfigException, OverrideParseException
from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from ..app import CONF_DIR, CONFIG_NAME, quote_numeric_choices
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
    args = [f"experiment={name}", *quote_numeric_choices(overrides)]
    try:
        return _compose(args)
    except HydraException as error:
        raise ReportError(_hydra_error(error, args)) from None


def variant_of(cfg: DictConfig) -> str:
    """The variant ``cfg`` describes; the baseline for a config composed without Hydra's part."""
    return str(OmegaConf.select(cfg, "hydra.job.override_dirname", default=BASELINE))


def one_line(error: BaseException) -> str:
    """``error`` as one line: its key, if it names one, and the first line of its message."""
    if isinstance(error, HydraException):
        return _hydra_error(error, [])
    if isinstance(error, OmegaConfBaseException) and error.full_key:
        return f"{error.full_key}: {_first_line(error.msg or str(error))}"
    return _first_line(str(error)) or type(error).__name__


def _compose(overrides: Sequence[str], hydra_part: bool = True) -> DictConfig:
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(CONFIG_NAME, overrides=list(overrides), return_hydra_config=hydra_part)


def _hydra_error(error: HydraException, overrides: Sequence[str]) -> str:
    if isinstance(error, MissingConfigException) and error.options and "/" in (error.missing_cfg_file or ""):
        group, option = error.missing_cfg_file.rsplit("/", 1)
        options = sorted(error.options, key=lambda o: (not o.isdigit(), int(o) if o.isdigit() else 0, o))
        return f"{group}={option}: no such option; allowed: {', '.join(options)}"
    if isinstance(error, OverrideParseException):
        lines = str(error).splitlines()
        return ": ".join(lines[:2])
    cause = error.__cause__
    if isinstance(cause, OmegaConfBaseException) and cause.full_key:
        return f"{cause.full_key}: no such key; {_keys_near(cause.full_key, overrides)}"
    return _first_line(str(error))


def _keys_near(full_key: str, overrides: Sequence[str]) -> str:
    """The keys next to ``full_key``, from the config composed without the override that set it."""
    others = [a for a in overrides if a.split("=", 1)[0].lstrip("+~") != full_key]
    try:
        cfg = _compose(others, hydra_part=False)
    except HydraException:
        return "check the spelling"
    parent = full_key.rpartition(".")[0]
    while parent and not isinstance(OmegaConf.select(cfg, parent), DictConfig):
        parent = parent.rpartition(".")[0]
    node = OmegaConf.select(cfg, parent) if parent else cfg
    return f"{f'keys of {parent}' if parent else 'top-level keys'}: {', '.join(map(str, node.keys()))}"


def _first_line(text: str) -> str:
    return next((line.strip() for line in text.splitlines() if line.strip()), "")


USER_ERRORS = (ReportError, HydraException, OmegaConfBaseException, OSError, ValueError)
"""What a reporting command reports as one line: mistakes in the command or missing runs.
Anything else is a bug and keeps its traceback."""
