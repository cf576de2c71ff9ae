"""result.json's text, both ways.

Strict JSON (every JSON reader takes it): a non-finite number is written as null, except in the
run's config, where ``inf`` is a value some keys document (``algorithm.huber_delta``,
``algorithm.max_grad_norm``: config/finite.py) and must come back as infinity, or resuming the
same command would find "another configuration". There it is written as the string ``"inf"``,
as Hydra's command line spells it.

``checksum`` is the SHA-256 of the record without it, in a canonical form, recorded when the
run is written: a later edit of any number (a plausible one included) no longer matches it.
Records written before it existed have none; check.py judges them by their consistency alone.
"""

from __future__ import annotations

import hashlib
import json
import math
from typing import Any

CHECKSUM = "checksum"
_INFINITY = {"inf": math.inf, "-inf": -math.inf}


def encode(data: dict[str, Any]) -> str:
    """The text of result.json for the record ``data`` (plain JSON types and floats)."""
    record = {k: _config_values(v) if k == "config" else _finite_or_null(v) for k, v in data.items()}
    record[CHECKSUM] = checksum(record)
    return json.dumps(record, indent=2, allow_nan=False) + "\n"


def decode(record: dict[str, Any]) -> dict[str, Any]:
    """``record`` as read from result.json with its config's infinities restored (checksum kept)."""
    if isinstance(record.get("config"), dict):
        record = {**record, "config": _restore(record["config"])}
    return record


def checksum(record: dict[str, Any]) -> str:
    """SHA-256 of ``record`` without its checksum; key order and whitespace do not count."""
    body = {k: v for k, v in record.items() if k != CHECKSUM}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()


def _finite_or_null(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite_or_null(v) for v in value]
    return value


def _config_values(value: Any) -> Any:
    if isinstance(value, float) and math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if isinstance(value, dict):
        return {k: _config_values(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_config_values(v) for v in value]
    return _finite_or_null(value)


def _restore(value: Any) -> Any:
    if isinstance(value, str):
        return _INFINITY.get(value, value)
    if isinstance(value, dict):
        return {k: _restore(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_restore(v) for v in value]
    return value
