"""The numbers a run is configured with are finite, except where infinity means something.

Hydra reads ``inf`` and ``nan`` as floats, and a key's own range check (``> 0``) lets ``inf``
through: ``algorithm.adam_epsilon=inf`` ran, and made every update zero. Every numeric key of a
run (its learner's, representation's, strategy's and world's, and ``threshold``) is refused here
unless it is finite, or it is one of ``INFINITY_MEANS``, whose documented meaning of ``inf`` a
run keeps: result.json writes it as ``"inf"`` (stored/codec.py), so the same command resumes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any, Iterator

INFINITY_MEANS: dict[tuple[str, str], str] = {
    ("dqn", "huber_delta"): "the squared TD error (a Huber loss without its linear part)",
    ("dqn", "max_grad_norm"): "no gradient clipping (as null)",
}
"""(algorithm option, key) -> what ``inf`` means for it; any other key must be finite."""


def check_finite(groups: Iterable[tuple[str, str | None, Mapping[str, Any]]]) -> None:
    """ValueError (one line, naming the key) for a non-finite number a run cannot run with.
    ``groups``: (config group, its option, its keys), e.g. ("algorithm", "dqn", {...}); "" for
    the top level."""
    for group, option, params in groups:
        for key, value in _numbers(params):
            if math.isfinite(value) or (value == math.inf and (option, key) in INFINITY_MEANS):
                continue
            name = f"{group}.{key}" if group else key
            allowed = ", ".join(f"algorithm.{k} (algorithm={a})" for a, k in INFINITY_MEANS)
            raise ValueError(f"{name} must be a finite number, got {value!r} (inf is allowed only for "
                             f"{allowed})")


def _numbers(values: Any, prefix: str = "") -> Iterator[tuple[str, float]]:
    """(dotted key, value) of every float in ``values``, nested mappings and lists included."""
    if isinstance(values, dict):
        for key, value in values.items():
            yield from _numbers(value, f"{prefix}.{key}" if prefix else str(key))
    elif isinstance(values, (list, tuple)):
        for i, value in enumerate(values):
            yield from _numbers(value, f"{prefix}[{i}]")
    elif isinstance(values, float):
        yield prefix, values
