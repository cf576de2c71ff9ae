"""Config dataclasses from plain mappings (what Hydra and the command line hand over)."""

from __future__ import annotations

from dataclasses import fields
from typing import Any, Mapping


def config_from_mapping(cls, values: Mapping[str, Any], group: str):
    """``cls(**values)``; a key ``cls`` lacks is an error naming the group, the unknown keys and
    the allowed ones, so a misspelt override fails before any work starts."""
    allowed = [f.name for f in fields(cls)]
    unknown = sorted((str(k) for k in values if k not in allowed))
    if unknown:
        raise ValueError(
            f"{group}: unknown key(s) {', '.join(unknown)}; allowed: {', '.join(allowed)}"
        )
    return cls(**values)
