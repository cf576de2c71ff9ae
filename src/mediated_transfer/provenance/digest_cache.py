"""Run digests remembered between processes, as Python remembers bytecode: valid while every
source file they were computed from has the same modification time and size.

Digesting a run's code imports its learner, strategy and world and walks their closure (about
0.3 s, and the imports); a sweep's preflight, a report and each job ask for it again in every
process. An entry is keyed by what chooses a run's roots (its options' names and ``_target_``
paths, where its packages are, the Python and the libraries) and lists every file of the
project's and its plugins' modules that were loaded when it was computed: a superset of the
files its closure read, so any change to one of them, or a file gone, makes the entry unusable
and the digest is computed again. The cache lives in the user's cache folder
(``$XDG_CACHE_HOME``, else ``~/.cache``); ``MEDIATED_TRANSFER_DIGEST_CACHE=off`` turns it off.
A cache that cannot be read or written is never an error: the digest is computed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import importlib.util
import json
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from ..atomic import atomic_write_text

if TYPE_CHECKING:
    from ..runspec import RunSpec

SWITCH = "MEDIATED_TRANSFER_DIGEST_CACHE"
_STARTED_NS = time.time_ns()
"""About when this process imported its code: a file changed since then may not be what it runs."""


def folder() -> Path | None:
    if os.environ.get(SWITCH, "").lower() in ("off", "0", "false", "no"):
        return None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "mediated-transfer" / "digests"


def key(spec: "RunSpec", lockstep: bool, scheme: int, versions: dict) -> str | None:
    """The entry's name for ``spec``'s run kind; None when a package it names cannot be found."""
    chosen = {f.name: getattr(spec, f.name) for f in dataclasses.fields(spec)
              if f.name in ("algorithm", "representation", "strategy") or f.name.endswith("_target")}
    chosen["world"] = f"{type(spec.world).__module__}.{type(spec.world).__qualname__}"
    places = {}
    for top in sorted({"mediated_transfer"} | {str(v).split(".")[0] for k, v in chosen.items()
                                               if k.endswith("_target") and v}):
        found = importlib.util.find_spec(top)
        if found is None or found.origin is None:
            return None
        places[top] = found.origin
    text = json.dumps([scheme, lockstep, chosen, places, sys.version, versions], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def read(name: str | None) -> str | None:
    """The remembered digest of entry ``name``, if every file it lists is unchanged."""
    where = folder()
    if name is None or where is None:
        return None
    try:
        entry = json.loads((where / f"{name}.json").read_text())
        for path, (mtime, size) in entry["files"].items():
            stat = os.stat(path)
            if stat.st_mtime_ns != mtime or stat.st_size != size:
                return None
        return str(entry["digest"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def write(name: str | None, digest: str, packages: set[str]) -> None:
    """Remember ``digest`` under ``name``, with the files of every loaded module of ``packages``."""
    where = folder()
    if name is None or where is None or "__main__" in packages:
        return
    files = {}
    for module_name, module in list(sys.modules.items()):
        path = getattr(module, "__file__", None)
        if module_name.split(".")[0] in packages and path:
            try:
                stat = os.stat(path)
            except OSError:
                return
            if stat.st_mtime_ns >= _STARTED_NS:
                return  # edited while this process ran: its digest may be of the code before
            files[path] = [stat.st_mtime_ns, stat.st_size]
    with contextlib.suppress(OSError):
        atomic_write_text(where / f"{name}.json", json.dumps({"digest": digest, "files": files}) + "\n")
