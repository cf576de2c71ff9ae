"""Which code computed a result, and whether a stored result is stale.

Every result records the git commit and whether the working tree was dirty (for people), and a
digest of the code the run executes (for the staleness check): the closure of its roots, its run
loop, learner, representation, strategy and world, each chosen by its config (closure.py). So a
change makes stale exactly the runs whose code it changes: adding a strategy, a learner, a
plugin, an unused function, or moving and renaming files, leaves every result current; changing
a constant of Algorithm 2 makes the scaffolded runs stale and no other. Plugin runs record their
plugin's identity and version too. Results of an older results format are stale.

Results recorded before this scheme (a digest of whole files), or before a refactor that was
shown to compute the same curves, stay current through ``translations.json``: each step maps
the digests of one commit to those of a later one, per run kind, and says why they compute the
same. carry_over.py writes a step when each moved kind's standing short run reproduced its
committed fingerprint (standing.py, fingerprints.json); the steps before fingerprints existed
were written from reruns by hand (docs/reliability.md lists their evidence). The digest covers this project's and its plugins' code only: another
numpy, torch or pymunk version, or another Python, is not seen by it; the versions a run
computed with are recorded beside it (``versions``), for people comparing runs across machines.

Whether a stored run is reused, recomputed, set aside or reported stale is judged in one place,
judge.py, for the sweep, the launchers and the reports alike.
"""

from __future__ import annotations

import functools
import json
import platform
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..results import RESULTS_FORMAT  # noqa: F401 - read here by staleness and its callers
from . import digest_cache
from .closure import PROJECT, closure_digest

if TYPE_CHECKING:
    from ..runspec import RunSpec

SCHEME = 3
"""Version of the code digest (3: the closure of a run's roots; 2: whole computing files)."""
PACKAGE = Path(__file__).resolve().parents[1]
TRANSLATIONS = Path(__file__).with_name("translations.json")
LIBRARIES = ("numpy", "numba", "torch", "pymunk", "gymnasium", "stable-baselines3")
"""Third-party code that computes a run, which the digest does not follow."""


def run_roots(spec: "RunSpec", lockstep: bool = False) -> list[Any]:
    """What computes ``spec``'s run: its loop, learner, representation, strategy and world."""
    from ..env.door import world_class
    from ..learners.factory import learner_target, representation_target
    from ..run import execute_run, own_run_loop

    loop = own_run_loop(spec) or execute_run
    roots = [loop, learner_target(spec.algorithm, spec.algorithm_target), spec.strategy_class(),
             world_class(spec.world_target)]
    features = representation_target(spec.representation, spec.representation_target)
    if features is not None:
        roots.append(features)
    if lockstep:
        from ..lockstep.run import execute_lockstep

        roots.append(execute_lockstep)
    return roots


def run_kind(spec: "RunSpec", lockstep: bool = False) -> str:
    """The key of a run's code in translations.json: algorithm/representation/strategy[/lockstep]."""
    return f"{spec.algorithm}/{spec.representation}/{spec.strategy}" + ("/lockstep" if lockstep else "")


def run_digest(spec: "RunSpec", lockstep: bool = False) -> str:
    """The digest of the code that computes ``spec`` (remembered between processes while its
    files are unchanged: digest_cache.py)."""
    entry = digest_cache.key(spec, lockstep, SCHEME, library_versions())
    digest = digest_cache.read(entry)
    if digest is None:
        roots = run_roots(spec, lockstep)
        digest = _digest(tuple(_path(r) for r in roots), tuple(roots))
        digest_cache.write(entry, digest, {PROJECT} | {_top(r) for r in roots})
    return digest


@functools.lru_cache(maxsize=256)
def _digest(key: tuple[str, ...], roots: tuple) -> str:
    return closure_digest(roots)


def code_version(spec: "RunSpec", lockstep: bool = False) -> dict[str, Any]:
    """``{"commit", "dirty", "digest", "scheme", "algorithm", "versions", "plugins"}`` of the code
    that computes ``spec`` in this process (commit/dirty None without git); ``lockstep``: computed
    in a group."""
    from .. import plugins

    version: dict[str, Any] = {"commit": _git("rev-parse", "HEAD"), "dirty": _dirty(),
                               "digest": run_digest(spec, lockstep), "scheme": SCHEME,
                               "algorithm": spec.algorithm, "versions": library_versions()}
    # A root's package by the class it is bound to: a plugin learner that inherits a built-in's
    # ``from_params`` is the plugin's.
    foreign = [plugins.identity(r) for r in run_roots(spec, lockstep) if plugins.package_of(r) != PROJECT]
    if foreign:
        version["plugins"] = foreign
    if lockstep:
        version["lockstep"] = True
    return version


@functools.cache
def library_versions() -> dict[str, str | None]:
    """Python's version and each of LIBRARIES' as installed (None: not installed), read from the
    packages' metadata: nothing is imported for it (a linear run never imports torch)."""
    from importlib import metadata

    versions: dict[str, str | None] = {"python": platform.python_version()}
    for name in LIBRARIES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def staleness(recorded: dict[str, Any] | None, results_format: int | None, spec: "RunSpec") -> str | None:
    """Why a result of ``spec`` recorded with ``recorded`` code is stale now; None when current."""
    if results_format != RESULTS_FORMAT:
        return f"results format {results_format or 1}, current {RESULTS_FORMAT}"
    recorded = recorded or {}
    lockstep = bool(recorded.get("lockstep"))
    try:
        current = run_digest(spec, lockstep)
    except (ValueError, ImportError) as error:  # a plugin, or a learner's dependency, not importable now
        return f"its code cannot be found now ({type(error).__name__}: {error})"
    digest = translate(recorded.get("digest"), run_kind(spec, lockstep))
    if digest != current:
        commit = recorded.get("commit") or "unknown"
        dirty = " (dirty)" if recorded.get("dirty") else ""
        return (f"computed by other code: commit {commit[:10]}{dirty}, code digest "
                f"{recorded.get('digest')}; now {str(_git('rev-parse', 'HEAD'))[:10]}, {current}")
    return None


def translate(digest: str | None, kind: str) -> str | None:
    """``digest`` carried through every step of translations.json for runs of ``kind``."""
    for step in _translations():
        digest = step["map"].get(kind, {}).get(digest, digest)
    return digest


@functools.cache
def _translations() -> list[dict]:
    if not TRANSLATIONS.is_file():
        return []
    return json.loads(TRANSLATIONS.read_text())["steps"]


def append_translation(step: dict) -> None:
    """Append ``step`` ({"why", "from_commit", "to_commit", "to_scheme", "map": {kind: {old:
    new}}}) to translations.json: the one writer of that file (for carry_over.py)."""
    from ..atomic import atomic_write_text

    steps = list(_translations()) + [step]
    atomic_write_text(TRANSLATIONS, json.dumps({"steps": steps}, indent=1, sort_keys=True) + "\n")
    _translations.cache_clear()


def _path(obj: Any) -> str:
    return f"{getattr(obj, '__module__', '')}.{getattr(obj, '__qualname__', repr(obj))}"


def _top(obj: Any) -> str:
    from .closure import _top as top, _underlying

    return top(_underlying(obj))


@functools.cache
def _git(*args: str) -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(PACKAGE), *args], capture_output=True, text=True,
                             timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip()


def _dirty() -> bool | None:
    status = _git("status", "--porcelain", "--untracked-files=no")
    return None if status is None else bool(status)
