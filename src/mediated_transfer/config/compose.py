"""From command-line overrides to a composed, checked config, or one line saying what is wrong.

Used by the entry point (before Hydra starts anything), by reporting and by tuning, so that all
three accept the same overrides and refuse the same mistakes with the same messages:

- a wrong type (``env.goal_radius=abc``) or an unknown option (``scale=smok``): Hydra's
  multi-line error, condensed to one line naming the override and the allowed options;
- an unknown key, also one added with ``+`` (``+algoritm=dqn``, which Hydra itself would
  accept): refused, naming the nearest valid key;
- ``n_source=<k>`` for any k >= 0, although the group's files hold only the paper's values.
"""

from __future__ import annotations

import dataclasses
import difflib
import re
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import HydraException, MissingConfigException
from omegaconf import DictConfig, OmegaConf, open_dict
from omegaconf.errors import OmegaConfBaseException

from . import schema
from .conf_dir import CONF_DIR, CONFIG_NAME  # noqa: F401 - read from here by most callers

NUMERIC_GROUPS = ("n_source",)
"""Config groups whose options are numbers: their choices are quoted for Hydra."""


class ConfigError(ValueError):
    """A configuration that cannot run; the message (one line) names the key and what is allowed."""


# --- overrides as typed on the command line ------------------------------------------------------


def prepare_overrides(overrides: Sequence[str]) -> list[str]:
    """Numeric group choices as Hydra needs them (``n_source=7`` -> ``n_source='7'``, also in
    sweeps: ``n_source=1,7``, ``choice(1,7)``, ``range(1,3)``), with an option registered for
    any N_source >= 0 that conf/ has no file for; a misspelt ``tuned`` choice refused.

    Hydra reads an unquoted 7 as the integer 7 and rejects it as a group choice, whose options
    are names; quoting keeps the natural spelling usable.
    """
    dirs = _searchpath(overrides)
    out = []
    for arg in overrides:
        _check_tuned_choice(arg, dirs)
        try:
            [override] = OverridesParser.create().parse_overrides([arg])
        except HydraException as error:
            raise ConfigError(f"{arg}: {first_line(str(error))}") from None
        group = override.get_key_element()
        if group not in NUMERIC_GROUPS or override.is_delete():
            out.append(arg)
            continue
        if override.is_sweep_override() and not override.is_discrete_sweep():
            raise ConfigError(f"{arg}: {group} takes integers; sweep them as a list or range")
        texts = list(override.sweep_string_iterator()) if override.is_sweep_override() \
            else [override.get_value_element_as_str()]
        values = [_numeric_choice(group, text.strip().strip("'\"").strip()) for text in texts]
        present = {p.stem for p in (CONF_DIR / group).glob("*.yaml")}
        schema.register_n_source([v for v in values if str(v) not in present])
        out.append(f"{group}=" + ",".join(f"'{v}'" for v in values))
    return out


def _numeric_choice(group: str, text: str) -> int:
    if not text.isdigit():
        options = sorted((p.stem for p in (CONF_DIR / group).glob("*.yaml")), key=int)
        raise ConfigError(f"{group}={text}: no such option; allowed: {', '.join(options)}, "
                          "or any other integer >= 0")
    return int(text)


def _searchpath(overrides: Sequence[str]) -> list[Path]:
    """The command's plugin folders, each checked (config/searchpath.py); the tuned options of
    its learners that extend a built-in registered (config/tuned.py)."""
    from .searchpath import searchpath_dirs
    from .tuned import register_inherited

    try:
        dirs = searchpath_dirs(overrides)
    except HydraException as error:
        raise ConfigError(first_line(str(error))) from None
    except ValueError as error:
        raise ConfigError(str(error)) from None
    register_inherited(dirs)
    return dirs


def _check_tuned_choice(arg: str, search_dirs: Sequence[Path]) -> None:
    # `tuned` is an optional group (a learner without Table I values has no file), so Hydra
    # would silently skip a misspelt choice: refuse it here.
    from .tuned import tuned_options

    match = re.fullmatch(r"tuned=([\w.-]+)", arg)
    if match:
        allowed = tuned_options(search_dirs)
        if match.group(1) not in allowed:
            raise ConfigError(f"tuned={match.group(1)}: no such option; allowed: {', '.join(allowed)}")


# --- composing -------------------------------------------------------------------------------------


@contextmanager
def hydra_context() -> Iterator[None]:
    """Hydra's compose API on conf/ (reuses an initialised Hydra, e.g. inside a job)."""
    if GlobalHydra.instance().is_initialized():
        yield
        return
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        yield


def compose_config(overrides: Sequence[str], hydra: bool = False) -> DictConfig:
    """The composed config of ``overrides`` (as typed); ConfigError in one line if it is wrong."""
    overrides = prepare_overrides(overrides)
    try:
        with hydra_context():
            cfg = compose(CONFIG_NAME, overrides=list(overrides), return_hydra_config=True)
    except (HydraException, OmegaConfBaseException) as error:
        raise ConfigError(one_line(error)) from None
    _remember_search_dirs(cfg)
    if not hydra:
        with open_dict(cfg):
            del cfg["hydra"]
    check_known_keys(cfg)
    return cfg


_SEARCH_DIRS: list[Path] = []
__process_state__ = ("_SEARCH_DIRS",)
"""What this module remembers of the process, not code: out of every run's code digest."""


def _remember_search_dirs(cfg: DictConfig) -> None:
    _SEARCH_DIRS[:] = source_dirs(OmegaConf.select(cfg, "hydra.runtime.config_sources") or [])


def source_dirs(sources: Sequence[Any]) -> list[Path]:
    """The folders of Hydra's ``hydra.runtime.config_sources`` beside conf/ (hydra.searchpath,
    SearchPathPlugins): a user's plugin folders."""
    dirs = [_source_dir(str(s.schema), str(s.path)) for s in sources if str(s.provider) not in ("hydra", "main")]
    return [d for d in dirs if d is not None and d != CONF_DIR]


def _source_dir(schema: str, path: str) -> Path | None:
    if schema == "file":
        return Path(path).resolve()
    if schema == "pkg":
        from importlib import resources

        try:
            return Path(str(resources.files(path.replace("/", "."))))
        except (ModuleNotFoundError, TypeError):
            return None
    return None


def search_dirs() -> list[Path]:
    """The config folders beside conf/ that the last composed config was searched in."""
    return list(_SEARCH_DIRS)


def one_line(error: BaseException) -> str:
    """Hydra's and OmegaConf's messages, condensed to the line that says what is wrong."""
    if isinstance(error, MissingConfigException):
        missing = str(error.missing_cfg_file or "")
        group, _, option = missing.rpartition("/")
        # Numbers (n_source) in numeric order, names alphabetically.
        options = sorted(error.options or [], key=lambda o: (not o.isdigit(), int(o) if o.isdigit() else 0, o))
        if group:
            return f"{group}={option}: no such option; allowed: {', '.join(options)}"
        return first_line(str(error))
    text = first_line(str(error))
    cause = error.__cause__ or error.__context__
    unknown = re.match(r"Could not override '([\w.]+)'", text)
    if unknown and cause is not None and "not in" in str(cause):
        return _unknown_key_message(unknown.group(1), _schema_fields(str(cause)))
    if cause is not None and str(cause).strip():
        detail = first_line(str(cause))
        full_key = re.search(r"full_key: (\S+)", str(cause))
        if full_key and full_key.group(1) not in text + detail:
            detail += f" (key {full_key.group(1)})"
        text = f"{text.removeprefix('Error merging override ')}: {detail}"
    return text


def first_line(text: str | BaseException) -> str:
    """The first non-empty line of a (multi-line) message."""
    text = str(text)
    lines = [line.strip() for line in text.strip().splitlines() if line.strip()]
    return lines[0] if lines else text.strip()


# --- unknown keys ------------------------------------------------------------------------------------


def check_known_keys(cfg: DictConfig) -> None:
    """Every key of ``cfg`` is a field of its node's schema; else ConfigError naming the nearest.

    Hydra lets ``+key=value`` add a key to any node (it opens struct mode for it), so a typo
    added that way (``+algoritm=dqn``, ``+scale.foo=1``) would otherwise run a default run.
    """
    for path, unknown, allowed in _unknown_keys(cfg, ""):
        raise ConfigError(_unknown_key_message(path + unknown, allowed))


def _unknown_key_message(key: str, allowed: list[str]) -> str:
    path, _, name = key.rpartition(".")
    prefix = f"{path}." if path else ""
    nearest = difflib.get_close_matches(name, allowed, n=1, cutoff=0.7)
    hint = f"did you mean '{prefix}{nearest[0]}'?" if nearest else f"keys here: {', '.join(allowed)}"
    return f"unknown key '{key}'; {hint}"


def _schema_fields(message: str) -> list[str]:
    """Fields of the schema named in OmegaConf's "Key 'x' not in 'LinearQOption'"."""
    named = re.search(r"not in '(\w+)'", message)
    classes = [schema.RunConfig, schema.ScaleConfig, schema.PathsConfig, schema.TrackingConfig,
               schema.ReportConfig, *(c for g in schema.PYTHON_OPTIONS.values() for c in g.values())]
    for cls in classes:
        if named and cls.__name__ == named.group(1):
            return [f.name for f in dataclasses.fields(cls)]
    return []


def _unknown_keys(node: Any, path: str):
    if not isinstance(node, DictConfig):
        return
    kind = OmegaConf.get_type(node)
    if path == "env." and node.get("_target_") not in (None, schema.WorldOption._target_):
        kind = _world_schema(node) or kind  # a world of one's own: its own keys
    if dataclasses.is_dataclass(kind):
        allowed = [f.name for f in dataclasses.fields(kind)]
        if path == "env.":
            allowed.append("_target_")
        if not path:
            allowed.append("hydra")  # Hydra's own node, present when composed with it
        for key in node.keys():
            if key not in allowed:
                yield path, str(key), allowed
    for key in node.keys():
        if str(key) == "hydra" and not path:
            continue
        yield from _unknown_keys(node._get_node(key), f"{path}{key}.")


def _world_schema(node: DictConfig) -> type | None:
    """The config_class of the world an ``env`` node names: its keys are the node's allowed
    ones (None if it cannot be imported: the run's checks then say so in one line)."""
    from ..env.door import world_class

    try:
        return world_class(node.get("_target_")).config_class
    except ValueError:
        return None
