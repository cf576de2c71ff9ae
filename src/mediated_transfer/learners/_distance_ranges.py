"""Validation shared by the representation configs: numbers where numbers belong, and the
|MiT| (tool_target) and |MiO| (tool_origin) ranges each a finite interval."""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np

RANGE_KINDS = ("tool_target", "tool_origin")


def check_numbers_and_ranges(config) -> None:
    for f in fields(config):
        value = getattr(config, f.name)
        if f.type == "float" and (isinstance(value, bool) or not isinstance(value, (int, float))):
            raise ValueError(f"representation.{f.name} must be a number, got {value!r}")
    for kind in RANGE_KINDS:
        low, high = getattr(config, f"{kind}_low"), getattr(config, f"{kind}_high")
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(
                f"representation.{kind}_low must be < representation.{kind}_high "
                f"(both finite), got {low!r} and {high!r}"
            )


def check_positive_int(config, name: str) -> None:
    value = getattr(config, name)
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"representation.{name} must be an integer >= 1, got {value!r}")
