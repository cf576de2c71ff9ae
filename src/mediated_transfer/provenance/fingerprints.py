"""fingerprints.json: per run kind, the code digest at which its standing run's fingerprint was
taken, and the fingerprint (standing.py). Committed with the code; carry_over.py writes it.

tests/test_standing.py checks that every kind's digest now is its entry's: so code that changes
what a kind executes cannot land without either carrying the kind's results over (its standing
run reproduced the fingerprint) or accepting that it computes something else.

One line per kind, so that a change shows in a diff as the kinds it touched.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

from ..atomic import atomic_write_text

FINGERPRINTS = Path(__file__).with_name("fingerprints.json")


@dataclass(frozen=True)
class Entry:
    digest: str
    """The kind's code digest when its fingerprint was last taken or reproduced."""
    fingerprint: str
    commit: str | None
    """The commit that code was at (None: no git), and whether the tree had changes beside it."""
    dirty: bool | None
    versions: str
    """The Python, libraries and machine the fingerprint was last taken or reproduced with."""
    why: str | None = None
    """Why it was accepted as computing something else than before (``carry_over --accept``)."""


def load(path: Path | None = None) -> dict[str, Entry]:
    path = path or FINGERPRINTS
    if not path.is_file():
        return {}
    return {kind: Entry(**entry) for kind, entry in json.loads(path.read_text())["kinds"].items()}


def save(entries: dict[str, Entry], path: Path | None = None) -> None:
    lines = [f" {json.dumps(kind)}: {json.dumps(_plain(entries[kind]), sort_keys=True)}" for kind in sorted(entries)]
    atomic_write_text(path or FINGERPRINTS, '{"kinds": {\n' + ",\n".join(lines) + "\n}}\n")


def _plain(entry: Entry) -> dict:
    return {key: value for key, value in asdict(entry).items() if value is not None or key != "why"}
