"""A search space (conf/hparams_search/<file>.yaml): which keys a study varies, over what.

The file names the learner, the base overrides every trial starts from, the tuning seeds, the
scale, the number of trials, the sampler and, per Hydra override key, a range (``low``,
``high``, ``log``) or ``choices``, with ``why``. Loading checks it against the composed config,
so a misspelt key, a range of the wrong type or a table seed fails at once, in one line naming
the key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from omegaconf import OmegaConf

from ..config.compose import CONF_DIR

SEARCH_SPACE_DIR = CONF_DIR / "hparams_search"
FILE_KEYS = ("learner", "base", "seeds", "scale", "trials", "sampler", "params")
PARAM_KEYS = ("low", "high", "log", "choices", "why")
SAMPLERS = ("random",)
_MISSING = object()


class SearchSpaceError(ValueError):
    """A search-space file that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class Parameter:
    """One searched key: a float or integer range (log or linear), or a list of choices."""

    key: str
    """Hydra override key, e.g. algorithm.lambda_."""
    kind: str
    """float, int or choice."""
    low: float | None = None
    high: float | None = None
    log: bool = False
    choices: tuple = ()
    why: str = ""

    def distribution(self):
        from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

        if self.kind == "choice":
            return CategoricalDistribution(list(self.choices))
        if self.kind == "int":
            return IntDistribution(int(self.low), int(self.high), log=self.log)
        return FloatDistribution(float(self.low), float(self.high), log=self.log)

    def describe(self) -> str:
        """The range as Table I prints it: ``0.01 - 0.3 (log)`` or ``{true, false}``."""
        if self.kind == "choice":
            return "{" + ", ".join(override_value(c) for c in self.choices) + "}"
        return f"{self.low:g} - {self.high:g}" + (" (log)" if self.log else "")


@dataclass(frozen=True)
class SearchSpace:
    path: Path
    learner: str
    """Names the study: tuning/<learner>/."""
    base: tuple[str, ...]
    """Overrides every trial starts from (learner, no transfer)."""
    seeds: tuple[int, ...]
    """Tuning seeds (never table seeds)."""
    scale: str
    """conf/scale option of every run: the budget."""
    trials: int
    sampler_seed: int
    params: tuple[Parameter, ...]
    defaults: dict[str, Any] = field(default_factory=dict)
    """The provisional defaults of the searched keys: their values in the composed base config."""

    def run_overrides(self, values: Mapping[str, Any], seed: int) -> list[str]:
        """Overrides of the run of a trial with ``values`` at tuning seed ``seed``.

        tracking=none: a trial is tracked as one MLflow run of its own, not as three.
        """
        searched = [f"{p.key}={override_value(values[p.key])}" for p in self.params]
        return [*self.base, f"scale={self.scale}", "tracking=none", f"seed={seed}", *searched]

    def learner_pair(self) -> str:
        """``<algorithm>_<representation>`` of the base overrides: the name of its conf/tuned/ file."""
        choice = {o.split("=", 1)[0]: o.split("=", 1)[1] for o in self.base if "=" in o}
        return f"{choice.get('algorithm', 'linear_q')}_{choice.get('representation', 'rbf')}"

    def with_scale(self, scale: str | None) -> "SearchSpace":
        if scale is None or scale == self.scale:
            return self
        _check_scale("scale", scale)
        return SearchSpace(self.path, self.learner, self.base, self.seeds, scale, self.trials,
                           self.sampler_seed, self.params, self.defaults)

    def identity(self) -> dict[str, Any]:
        """What a trial's result depends on; a study refuses to continue with another identity."""
        return {
            "learner": self.learner,
            "base": list(self.base),
            "seeds": list(self.seeds),
            "scale": self.scale,
            "sampler_seed": self.sampler_seed,
            "params": {p.key: p.describe() for p in self.params},
        }


def override_value(value: Any) -> str:
    """A value as a Hydra override spells it (true/false, null, full float precision)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    return repr(value) if isinstance(value, float) else str(value)


def available_learners(folder: Path = SEARCH_SPACE_DIR) -> dict[str, Path]:
    """learner name -> its search-space file, for every file in ``folder``."""
    found = {}
    for path in sorted(folder.glob("*.yaml")):
        learner = OmegaConf.load(path).get("learner")
        if learner is not None:
            found[str(learner)] = path
    return found


def find_search_space(learner: str, folder: Path = SEARCH_SPACE_DIR) -> SearchSpace:
    files = available_learners(folder)
    if learner not in files:
        raise SearchSpaceError(
            f"learner={learner!r} has no search space in {folder}; allowed: {', '.join(files)}"
        )
    return load_search_space(files[learner])


def load_search_space(path: str | Path) -> SearchSpace:
    """Read and check a search-space file (composing its base config to check every key)."""
    from ..config.compose import ConfigError, compose_config

    path = Path(path)
    data = OmegaConf.to_container(OmegaConf.load(path), resolve=True)

    def fail(key: str, problem: str) -> None:
        raise SearchSpaceError(f"{path.name}: {key}: {problem}")

    if not isinstance(data, dict):
        fail("(file)", "must be a mapping of " + ", ".join(FILE_KEYS))
    for key in FILE_KEYS:
        if key not in data:
            fail(key, "missing; a search space needs " + ", ".join(FILE_KEYS))
    unknown = sorted(set(data) - set(FILE_KEYS))
    if unknown:
        fail(unknown[0], "unknown key; allowed: " + ", ".join(FILE_KEYS))

    learner, base, seeds, scale = data["learner"], data["base"], data["seeds"], data["scale"]
    if not isinstance(learner, str) or not learner.isidentifier():
        fail("learner", f"must be a name (letters, digits, _), got {learner!r}")
    if not isinstance(base, list) or not all(isinstance(o, str) and "=" in o for o in base):
        fail("base", f"must be a list of overrides key=value, got {base!r}")
    if any(o.split("=")[0].lstrip("+~") in ("seed", "scale") for o in base):
        fail("base", "must not set seed or scale (they are the keys seeds and scale)")
    if not isinstance(seeds, list) or not seeds or not all(_is_int(s) for s in seeds):
        fail("seeds", f"must be a non-empty list of integers, got {seeds!r}")
    if len(set(seeds)) != len(seeds):
        fail("seeds", f"must be distinct, got {seeds}")
    if not isinstance(scale, str):
        fail("scale", f"must name a conf/scale option, got {scale!r}")
    _check_scale(f"{path.name}: scale", scale)
    if not _is_int(data["trials"]) or data["trials"] < 1:
        fail("trials", f"must be an integer >= 1, got {data['trials']!r}")
    sampler = data["sampler"]
    if not isinstance(sampler, dict) or set(sampler) != {"name", "seed"}:
        fail("sampler", f"must be {{name: random, seed: <integer>}}, got {sampler!r}")
    if sampler["name"] not in SAMPLERS:
        fail("sampler.name", f"must be one of {', '.join(SAMPLERS)}, got {sampler['name']!r}")
    if not _is_int(sampler["seed"]):
        fail("sampler.seed", f"must be an integer, got {sampler['seed']!r}")
    if not isinstance(data["params"], dict) or not data["params"]:
        fail("params", "must map at least one override key to its range or choices")

    try:
        # The provisional defaults (the dataclasses'), not Table I's tuned values: the study
        # starts from them, and Table I compares them with what the study chose.
        cfg = compose_config([*base, "tuned=provisional"])
    except ConfigError as error:  # one line naming the key
        fail("base", f"does not compose: {str(error).splitlines()[0]}")
    table_seeds = int(cfg.scale.seeds)  # the default scale is the paper's: its seeds 0..n-1
    if str(cfg.scale.name) != "paper":
        fail("base", f"must leave the scale at its default (paper), got {cfg.scale.name}")
    in_tables = sorted(s for s in seeds if 0 <= s < table_seeds)
    if in_tables:
        fail("seeds", f"{in_tables} are table seeds (0-{table_seeds - 1}); tuning seeds must not be")
    if str(cfg.strategy.name) != "none" or int(cfg.n_source) != 0:
        fail("base", f"must tune without transfer (strategy=none, n_source=0), got "
                     f"strategy={cfg.strategy.name}, n_source={cfg.n_source}")

    params = []
    defaults = {}
    for key, spec in data["params"].items():
        current = OmegaConf.select(cfg, key, default=_MISSING)
        if current is _MISSING or isinstance(current, (dict, list)) or OmegaConf.is_config(current):
            group = key.split(".")[0]
            node = cfg.get(group)
            allowed = ", ".join(f"{group}.{k}" for k in node) if OmegaConf.is_dict(node) else "a leaf key"
            fail(f"params.{key}", f"no such value in the composed config; allowed: {allowed}")
        params.append(_parameter(key, spec, current, fail))
        defaults[key] = current
    return SearchSpace(path, learner, tuple(base), tuple(int(s) for s in seeds), scale,
                       int(data["trials"]), int(sampler["seed"]), tuple(params), defaults)


def _parameter(key: str, spec: Any, current: Any, fail) -> Parameter:
    name = f"params.{key}"
    if not isinstance(spec, dict):
        fail(name, f"must be a mapping with low/high[/log] or choices, got {spec!r}")
    unknown = sorted(set(spec) - set(PARAM_KEYS))
    if unknown:
        fail(f"{name}.{unknown[0]}", "unknown key; allowed: " + ", ".join(PARAM_KEYS))
    why = spec.get("why")
    if not isinstance(why, str) or not why.strip():
        fail(f"{name}.why", "missing: say why this range")
    if "choices" in spec:
        if {"low", "high", "log"} & set(spec):
            fail(name, "give either choices or low/high[/log], not both")
        choices = spec["choices"]
        if not isinstance(choices, list) or len(choices) < 2:
            fail(f"{name}.choices", f"must list at least two values, got {choices!r}")
        wrong = [c for c in choices if not _same_type(c, current)]
        if wrong:
            fail(f"{name}.choices", f"{wrong[0]!r} is not a {type(current).__name__} like the "
                                    f"config's value {current!r}")
        return Parameter(key, "choice", choices=tuple(choices), why=why.strip())

    if "low" not in spec or "high" not in spec:
        fail(name, "needs low and high (or choices)")
    low, high, log = spec["low"], spec["high"], spec.get("log", False)
    if isinstance(current, bool) or not isinstance(current, (int, float)):
        fail(name, f"the config's value {current!r} is not a number: give choices")
    kind = "int" if isinstance(current, int) else "float"
    for bound, value in (("low", low), ("high", high)):
        if kind == "int" and not _is_int(value):
            fail(f"{name}.{bound}", f"must be an integer (the config's value {current!r} is one), got {value!r}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            fail(f"{name}.{bound}", f"must be a finite number, got {value!r}")
    if not low < high:
        fail(name, f"low must be < high, got {low!r} and {high!r}")
    if not isinstance(log, bool):
        fail(f"{name}.log", f"must be true or false, got {log!r}")
    if log and low <= 0:
        fail(f"{name}.low", f"must be > 0 on a log scale, got {low!r}")
    return Parameter(key, kind, low, high, log, why=why.strip())


def _check_scale(where: str, scale: str) -> None:
    scales = sorted(p.stem for p in (CONF_DIR / "scale").glob("*.yaml"))
    if scale not in scales:
        raise SearchSpaceError(f"{where}: {scale!r} is not a conf/scale option; allowed: {', '.join(scales)}")


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _same_type(value: Any, current: Any) -> bool:
    if isinstance(current, bool) or isinstance(value, bool):
        return isinstance(current, bool) and isinstance(value, bool)
    if isinstance(current, float):
        return isinstance(value, (int, float))
    return type(value) is type(current)

