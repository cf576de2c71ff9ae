"""The one door for what a researcher extends (strategies, learners, representations): a
config node's ``_target_`` names a class or function by dotted path, Hydra-style, and the
framework calls it with the node's other keys. The built-ins come through it too.

Everything here checks a plugin before any work, in one line naming the key: not importable
(the dotted path and why), not implementing its interface (the missing method by name), a key
that is not one of its parameters (and the ones it has).
"""

from __future__ import annotations

import importlib.metadata
import inspect
from collections.abc import Iterable, Mapping
from typing import Any, Callable

TARGET = "_target_"


def locate(key: str, path: Any) -> Any:
    """The object ``path`` names; ValueError naming ``key`` if it cannot be imported."""
    if not isinstance(path, str) or not path.strip():
        raise ValueError(f"{key}._target_ must be a dotted path to a class or function, got {path!r}")
    from hydra.utils import get_object

    try:
        return get_object(path)
    except Exception as error:  # noqa: BLE001 - any import failure of a plugin is its user's to read
        cause = error.__cause__ or error
        reason = str(cause).strip().splitlines()[0] if str(cause).strip() else type(cause).__name__
        raise ValueError(f"{key}._target_={path}: not importable ({type(cause).__name__}: {reason})") from None


def owner_class(target: Any) -> type | None:
    """The class a target builds: the class itself, or the class of a classmethod."""
    if isinstance(target, type):
        return target
    owner = getattr(target, "__self__", None)
    return owner if isinstance(owner, type) else None


def check_interface(key: str, target: Any, methods: Iterable[str], interface: str) -> None:
    """ValueError naming the first method of ``methods`` that the target's class lacks."""
    cls = owner_class(target)
    if cls is None:
        if not callable(target):
            raise ValueError(f"{key}._target_={path_of(target)}: not a class or function")
        return  # a factory function: its product is checked when it is made
    for method in methods:
        if not hasattr(cls, method):
            raise ValueError(f"{key}._target_={path_of(target)}: {cls.__name__} does not implement "
                             f"the {interface} interface: no method '{method}'")


def check_parameters(key: str, target: Any, params: Mapping[str, Any], provided: Iterable[str] = ()) -> None:
    """ValueError naming a key of ``params`` that ``target`` does not take, or a parameter it
    needs that neither ``params`` nor the framework (``provided``) gives."""
    try:
        signature = inspect.signature(target)
    except (TypeError, ValueError):
        return
    parameters = signature.parameters
    takes_any = any(p.kind is p.VAR_KEYWORD for p in parameters.values())
    provided = set(provided)
    allowed = [n for n, p in parameters.items()
               if n not in provided and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    for name in params:
        if name in provided or (name not in parameters and not takes_any):
            raise ValueError(f"{key}.{name}: not a parameter of {path_of(target)}; "
                             f"allowed: {', '.join(allowed) or 'none'}")
    for name, p in parameters.items():
        if (p.default is p.empty and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
                and name not in params and name not in provided):
            raise ValueError(f"{key}.{name}: required by {path_of(target)} but not set")


def call(target: Callable, params: Mapping[str, Any], **provided: Any) -> Any:
    """``target(**params, **provided)``: what hydra.utils.instantiate does with a node."""
    return target(**dict(params), **provided)


def without_target(params: Mapping[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in params.items() if k != TARGET}


def path_of(target: Any) -> str:
    """The dotted path that names ``target``. A classmethod inherited by a plugin's class
    (``my_plugins.sarsa.Sarsa.from_params``, defined on the built-in learner) is named by the
    class it is bound to: its function alone would name the built-in."""
    owner = getattr(target, "__self__", None)
    if isinstance(owner, type):
        return f"{owner.__module__}.{owner.__qualname__}.{target.__name__}"
    module = getattr(target, "__module__", None) or type(target).__module__
    name = getattr(target, "__qualname__", None) or type(target).__qualname__
    return f"{module}.{name}"


def package_of(target: Any) -> str:
    """The top-level package of the code ``target`` names (a bound classmethod: its class's)."""
    return path_of(target).split(".")[0]


def identity(target: Any) -> dict[str, Any]:
    """What result.json records of a plugin: its dotted path, its distribution and version."""
    module = path_of(target).rsplit(".", 1)[0]
    top = module.split(".")[0]
    distributions = importlib.metadata.packages_distributions().get(top, [])
    version = None
    for name in distributions:
        try:
            version = importlib.metadata.version(name)
            break
        except importlib.metadata.PackageNotFoundError:
            continue
    return {"target": path_of(target), "distribution": distributions[0] if distributions else None,
            "version": version}
