"""Table I's tuned values for a plugin learner that extends a built-in one, and which tuned file
a run got.

conf/config.yaml picks the tuned file by the option names, ``tuned: ${algorithm}_${representation}``,
so a plugin option (``algorithm=sarsa``) would find none and silently run the built-in's
provisional defaults. Here every learner option on the search path whose class extends a
built-in learner (``my_plugins.sarsa.Sarsa(LinearQLearner)``, ``_target_`` ``...Sarsa.from_params``)
or whose YAML extends a built-in option (``defaults: [linear_q]``) gets a ``tuned`` option of its
own name (``sarsa_rbf``) holding the built-in's values (conf/tuned/linear_q_rbf.yaml), less the
``algorithm`` keys its YAML sets itself: those win. A plugin says otherwise with a file of its own,
``<its conf>/tuned/sarsa_rbf.yaml`` (``{}`` for none), or ``~tuned`` / ``tuned=...`` on the
command line.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from pathlib import Path

from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig, OmegaConf

from .. import plugins
from .conf_dir import CONF_DIR
from .schema import PYTHON_OPTIONS

GROUP = "tuned"
_META = ("defaults", "_target_", "name")
"""Keys of an algorithm YAML that are not the learner's hyperparameters."""
_INHERITED = "inherited from "
"""How an inherited option's provider (ConfigStore) names the built-in tuned file it copies; the
store travels to the launchers' workers (Hydra's singleton state), so they can say so too."""


def register_inherited(search_dirs: Sequence[Path]) -> None:
    """Register, for every plugin learner option in ``search_dirs`` that extends a built-in, the
    ``tuned`` options of the built-in's tuned files under the plugin's name (module doc)."""
    for option, builtin, own_keys in _extending_options(tuple(search_dirs)):
        for representation in PYTHON_OPTIONS["representation"]:
            source = CONF_DIR / GROUP / f"{builtin}_{representation}.yaml"
            name = f"{option}_{representation}"
            if not source.is_file() or any((d / GROUP / f"{name}.yaml").is_file() for d in search_dirs):
                continue
            values = OmegaConf.load(source)
            for key in own_keys:
                if "algorithm" in values and key in values.algorithm:
                    del values.algorithm[key]
            ConfigStore.instance().store(group=GROUP, name=name, node=values, package="_global_",
                                         provider=f"{_INHERITED}{source.stem}")


@functools.lru_cache(maxsize=16)
def _extending_options(search_dirs: tuple[Path, ...]) -> list[tuple[str, str, tuple[str, ...]]]:
    """(option, the built-in it extends, the algorithm keys its YAML sets) of the search path's
    learner options that extend a built-in."""
    found = []
    for folder in search_dirs:
        for path in sorted((folder / "algorithm").glob("*.yaml")):
            if path.stem in PYTHON_OPTIONS["algorithm"]:
                continue
            node = OmegaConf.load(path)
            builtin = _extended_builtin(node)
            if builtin is not None:
                found.append((path.stem, builtin, tuple(str(k) for k in node if k not in _META)))
    return found


def _extended_builtin(node: DictConfig) -> str | None:
    """The built-in learner option a plugin's YAML extends: by its ``_target_``'s class (the
    nearest built-in ancestor), else by its defaults list; None if neither."""
    target = node.get("_target_")
    if target is None:
        defaults = [d for d in node.get("defaults") or [] if isinstance(d, str)]
        return next((d for d in defaults if d in PYTHON_OPTIONS["algorithm"]), None)
    try:
        built = plugins.locate("algorithm", target)
    except ValueError:
        return None  # not importable: refused in one line if the option is chosen
    owner = plugins.owner_class(built)
    method = getattr(built, "__name__", None)
    if owner is None or method is None:
        return None
    builtins = {cls._target_: name for name, cls in PYTHON_OPTIONS["algorithm"].items()}
    for ancestor in owner.__mro__:
        name = builtins.get(f"{ancestor.__module__}.{ancestor.__qualname__}.{method}")
        if name is not None:
            return name
    return None


def _inherited() -> dict[str, str]:
    """The inherited ``tuned`` options registered in this process: option -> built-in file."""
    nodes = ConfigStore.instance().repo.get(GROUP, {})
    return {n.name.removesuffix(".yaml"): n.provider.removeprefix(_INHERITED)
            for n in nodes.values() if str(getattr(n, "provider", "")).startswith(_INHERITED)}


def tuned_options(search_dirs: Sequence[Path]) -> list[str]:
    """Every ``tuned`` option: conf/tuned/, the search path's, the inherited ones registered."""
    names = set(_inherited())
    for folder in (CONF_DIR, *search_dirs):
        names |= {p.stem for p in (Path(folder) / GROUP).glob("*.yaml")}
    return sorted(names)


def tuned_line(choices: Mapping[str, str | None], search_dirs: Sequence[Path]) -> str:
    """Which tuned file a run composed with Hydra's ``choices`` got, for its log."""
    chosen = choices.get(GROUP)
    who = f"algorithm={choices.get('algorithm')} representation={choices.get('representation')}"
    if not chosen:
        return f"tuned: none (~tuned): {who} runs its options' own defaults"
    for folder in (CONF_DIR, *search_dirs):
        path = Path(folder) / GROUP / f"{chosen}.yaml"
        if path.is_file():
            return f"tuned: {_shown(path)} applied to {who}"
    inherited = _inherited().get(chosen)
    if inherited is not None:
        return (f"tuned: {_shown(CONF_DIR / GROUP / f'{inherited}.yaml')} (Table I of the built-in learner that "
                f"algorithm={choices.get('algorithm')} extends) applied to {who}, less the keys its YAML sets")
    return f"tuned: none (no tuned file {chosen}.yaml): {who} runs its options' own defaults"


def _shown(path: Path) -> str:
    # conf/tuned/x.yaml as the docs name it; a plugin's file by its full path.
    return str(path.relative_to(CONF_DIR.parent)) if path.is_relative_to(CONF_DIR.parent) else str(path)
