"""The folders a command's ``hydra.searchpath=[...]`` adds beside conf/, checked before Hydra
reads them: Hydra only warns about a path it cannot read (a warning it also prints for a path
that works) and then refuses the plugin's options as unknown, never saying why.

A ``pkg://my_plugins.conf`` path must name an importable package (its folder on PYTHONPATH, or
installed) with an ``__init__.py`` (Hydra reads a pkg:// path only from a regular package); a
``file://`` path must be a folder. Anything else is one line naming the path and the fix.
"""

from __future__ import annotations

from collections.abc import Sequence
import importlib.util
from pathlib import Path

from hydra.core.override_parser.overrides_parser import OverridesParser

KEY = "hydra.searchpath"


def searchpath_entries(overrides: Sequence[str]) -> list[str]:
    """The entries of the ``hydra.searchpath`` overrides among ``overrides`` (as typed)."""
    entries: list[str] = []
    for arg in overrides:
        if not arg.lstrip("+~").startswith(KEY):
            continue
        [override] = OverridesParser.create().parse_overrides([arg])
        if override.get_key_element().lstrip("+~") != KEY or override.is_delete():
            continue
        value = override.value()
        entries += [str(v) for v in value] if isinstance(value, list) else [str(value)]
    return entries


def searchpath_dirs(overrides: Sequence[str]) -> list[Path]:
    """The folders of the command's search path; ValueError (one line) for one that cannot be read."""
    return [entry_dir(entry) for entry in searchpath_entries(overrides)]


def entry_dir(entry: str) -> Path:
    """The folder of one search path entry (``pkg://a.b``, ``file://dir`` or a bare folder)."""
    scheme, sep, path = entry.partition("://")
    if not sep:
        scheme, path = "file", entry
    if scheme == "file":
        folder = Path(path).resolve()
        if not folder.is_dir():
            raise ValueError(f"{KEY}: {entry}: no such folder ({folder})")
        return folder
    if scheme != "pkg":
        raise ValueError(f"{KEY}: {entry}: unknown scheme {scheme}://; allowed: pkg://, file://")
    module = path.replace("/", ".")
    top = module.split(".")[0]
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError) as error:
        spec, reason = None, f"{type(error).__name__}: {error}"
    else:
        reason = f"no module named {module!r}"
    if spec is None:
        raise ValueError(f"{KEY}: {entry}: {module} cannot be imported ({reason}); put the folder "
                         f"that holds {top}/ on PYTHONPATH, or pip install -e it")
    locations = list(spec.submodule_search_locations or [])
    if not locations:
        raise ValueError(f"{KEY}: {entry}: {module} is a module, not a package holding config folders")
    if spec.origin is None or not spec.origin.endswith("__init__.py"):
        raise ValueError(f"{KEY}: {entry}: {locations[0]} has no __init__.py; Hydra reads a pkg:// path "
                         "only from a package: add an empty one")
    return Path(locations[0])
