"""Which code computed a result, and whether a stored result is stale.

Every result records the git commit and whether the working tree was dirty (for people), and a
digest of the code of the source files that compute a run (for the staleness check): the world, the
learners, the transfer strategies, the run loop and the metrics. A change to reporting,
tracking, docs or configs does not make results stale; a change to anything a curve depends
on does. Results of an older results format are stale too. The digest covers this project's code
only: another numpy, torch or pymunk version, or another Python (ast.dump may differ), is not
seen, so it is a check for code changes, not a full environment record.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import subprocess
from pathlib import Path
from typing import Any

RESULTS_FORMAT = 2
"""Version of result.json's layout (2: code version and discovery step recorded)."""

PACKAGE = Path(__file__).resolve().parent
COMPUTING_SOURCES = ("env", "learners", "transfer", "run.py", "run_sb3.py", "metrics.py", "results.py")
"""What a run's curve depends on, relative to the package."""
_REPRESENTATION_SOURCES = ("learners/rbf.py", "learners/fsr.py", "learners/_distance_ranges.py")
_SB3_SOURCES = ("learners/sb3.py", "transfer/wrapper.py", "run_sb3.py", *_REPRESENTATION_SOURCES)
LEARNER_SOURCES = {
    "linear_q": ("learners/linear_q.py", *_REPRESENTATION_SOURCES),
    "dqn": ("learners/dqn.py", "learners/dqn_kernels.py"),
    "sb3_ppo": _SB3_SOURCES,
    "sb3_dqn": _SB3_SOURCES,
}
"""Files that only some algorithms run: a change to the DQN does not make linear results stale,
nor the other way round. A file listed for several algorithms counts for each of them."""
NOT_COMPUTING = ("env/render.py", "env/animate.py", "env/scripted.py")
"""In the computing folders but never called by a run: drawing, GIFs, scripted policies."""
REPORTING_DEFINITIONS = {
    "metrics.py": ("first_point_at_threshold", "learning_span"),
    "results.py": ("RunResult.learning_span",),
}
"""Definitions in computing files that only reports call (a run never does; tests check it):
left out of the digest, with the imports of them, so that adding one does not make results
stale. Results recorded before this list existed carry the digest of whole files; either
digest of the current code makes a result current (``staleness``)."""
LOCKSTEP_SOURCES = ("lockstep",)
"""The lockstep loop and its learner groups: in the digest of the runs they computed only, so a
change there does not make single runs stale (nor adding it, the results it reproduces)."""


@functools.cache
def code_version(algorithm: str | None = None, lockstep: bool = False) -> dict[str, Any]:
    """``{"commit", "dirty", "digest"}`` of the code in this process (commit/dirty None without
    git); with ``algorithm``, the digest covers only the code that runs it, and the record
    says so (``"algorithm"``); with ``lockstep``, it covers the lockstep loop too (``"lockstep"``)."""
    version = {"commit": _git("rev-parse", "HEAD"), "dirty": _dirty(),
               "digest": source_digest(algorithm=algorithm, lockstep=lockstep)}
    if algorithm is not None:
        version["algorithm"] = algorithm
    if lockstep:
        version["lockstep"] = True
    return version


def source_digest(package: Path = PACKAGE, algorithm: str | None = None, lockstep: bool = False,
                  whole_files: bool = False) -> str:
    """Digest of the computing sources' syntax trees, without the files only other algorithms
    run (and the lockstep loop's, unless ``lockstep``) and the definitions only reports call
    (unless ``whole_files``, the digest of results recorded before REPORTING_DEFINITIONS):
    comments, docstrings and layout do not change what a run computes, so they do not change
    the digest."""
    others = set(NOT_COMPUTING)
    if algorithm is not None:
        others |= {file for name, files in LEARNER_SOURCES.items() if name != algorithm for file in files}
        others -= set(LEARNER_SOURCES.get(algorithm, ()))
    digest = hashlib.sha256()
    for entry in COMPUTING_SOURCES + (LOCKSTEP_SOURCES if lockstep else ()):
        path = package / entry
        files = sorted(path.rglob("*.py")) if path.is_dir() else [path]
        for file in files:
            if file.relative_to(package).as_posix() in others:
                continue
            name = file.relative_to(package).as_posix()
            digest.update(name.encode())
            digest.update(_code_of(file.read_text(), () if whole_files else REPORTING_DEFINITIONS.get(name, ())).encode())
    return digest.hexdigest()[:16]


def _code_of(source: str, left_out: tuple[str, ...] = ()) -> str:
    tree = ast.parse(source)
    if left_out:
        _leave_out(tree, left_out)
    # Docstrings, of modules, classes, functions and fields, are string statements: drop them.
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list):
            node.body = [n for n in body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)
                                                 and isinstance(n.value.value, str))] or [ast.Pass()]
    return ast.dump(tree, annotate_fields=False)


def _leave_out(tree: ast.Module, names: tuple[str, ...]) -> None:
    """Drop the named definitions ("f" or "Class.f") and the names imported for them."""
    top = {n for n in names if "." not in n}
    methods: dict[str, set[str]] = {}
    for n in names:
        if "." in n:
            cls, _, method = n.partition(".")
            methods.setdefault(cls, set()).add(method)
    imported = {n.rpartition(".")[2] for n in names}
    kept = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name in top:
            continue
        if isinstance(node, ast.ClassDef) and node.name in methods:
            node.body = [n for n in node.body if not (isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
                                                      and n.name in methods[node.name])]
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            node.names = [a for a in node.names if a.name not in imported]
            if not node.names:
                continue
        kept.append(node)
    tree.body = kept


def staleness(recorded: dict[str, Any] | None, results_format: int | None) -> str | None:
    """Why a result recorded with ``recorded`` code is stale now; None when it is current."""
    if results_format != RESULTS_FORMAT:
        return f"results format {results_format or 1}, current {RESULTS_FORMAT}"
    algorithm, lockstep = (recorded or {}).get("algorithm"), bool((recorded or {}).get("lockstep"))
    current = code_version(algorithm, lockstep)
    digests = {current["digest"], _whole_files_digest(algorithm, lockstep)}
    if not recorded or recorded.get("digest") not in digests:
        commit = (recorded or {}).get("commit") or "unknown"
        dirty = " (dirty)" if (recorded or {}).get("dirty") else ""
        return (f"computed by other code: commit {commit[:10]}{dirty}, code digest "
                f"{(recorded or {}).get('digest')}; now {str(current['commit'])[:10]}, {current['digest']}")
    return None


@functools.cache
def _whole_files_digest(algorithm: str | None, lockstep: bool) -> str:
    return source_digest(algorithm=algorithm, lockstep=lockstep, whole_files=True)


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
