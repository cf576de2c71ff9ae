"""Config dataclasses from plain mappings (what Hydra and the command line hand over)."""

from __future__ import annotations

import difflib

from dataclasses import fields
from typing import Any, Mapping


def config_from_mapping(cls, values: Mapping[str, Any], group: str):
    """``cls(**values)``; a key ``cls`` lacks is an error naming the group, the unknown keys and
    the allowed ones, so a misspelt override fails before any work starts."""
    allowed = [f.name for f in fields(cls)]
    unknown = sorted((str(k) for k in values if k not in allowed))
    if unknown:
        nearest = {k: difflib.get_close_matches(k, allowed, n=1, cutoff=0.7) for k in unknown}
        hints = [f"'{group}.{near[0]}' for {k}" for k, near in nearest.items() if near]
        hint = f" (did you mean {', '.join(hints)}?)" if hints else ""
        raise ValueError(
            f"{group}: unknown key(s) {', '.join(unknown)}{hint}; allowed: {', '.join(allowed)}"
        )
    return cls(**values)
