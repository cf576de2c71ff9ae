"""Reading a stored run validates it: a record that cannot be trusted never reaches a table.

``load`` returns result.json's record only if it is whole and consistent:

- the file is a file, text, JSON, an object, and matches its checksum when it has one (codec.py);
- it has every key a run records and no other, each of its kind (a number where a number is
  due, finite where it must be: a curve, a reward loss, a time);
- its numbers agree with each other: the curve's points are its config's evaluation points,
  its reward loss and time to threshold are those of its curve;
- curve.csv holds the same curve.

Otherwise ``DamagedResult``, one line: the file and what is wrong with it. A record without a
checksum is damaged too: records carry one since issue 38, and those written before (the
committed paper-scale runs) were sealed once (seal.py), so a record without one had it deleted;
and only the checksum shows an edit of result.json and curve.csv that agree with each other.
``check_place`` judges a whole record against its folder: another cell's or seed's run there
(moved or copied) is not the folder's run, and is treated as damaged.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from . import CURVE_FILE, CURVE_HEADER, RESULT_FILE
from .codec import CHECKSUM, checksum, decode


class DamagedResult(ValueError):
    """A stored run that cannot be trusted; the message is one line: the file, what is wrong."""

    def __init__(self, path: Path, problem: str):
        self.path, self.problem = Path(path), problem
        super().__init__(f"{path}: {problem}")


FIELDS: dict[str, str] = {
    # RunResult's fields and the kind of value each holds (tests keep the two equal).
    "algorithm": "name", "representation": "name", "strategy": "name",
    "n_source": "count", "seed": "count", "budget": "positive",
    "steps": "steps", "mean_reward": "numbers", "success_rate": "rates",
    "reward_loss": "number or null", "time_to_threshold": "step or null",
    "source_phase_end": "step or null", "source_tasks_solved": "count",
    "wall_time_s": "seconds", "learning_steps_per_s": "speed or null",
    "learner_stats": "mapping", "first_target_reward_step": "step or null",
    "config": "mapping", "code": "mapping", "results_format": "count or null", "failure": "text or null",
    "choices": "mapping or null",
}
OPTIONAL = frozenset({"learner_stats", "first_target_reward_step", "config", "code", "results_format", "failure",
                      "choices"})
"""Keys that records of earlier formats may lack (RunResult's fields with defaults)."""

DEFAULT_SUCCESS_REWARD = 10.0
"""R_max of a record whose config does not say (WorldConfig.success_reward's default)."""
_TOLERANCE = 1e-9


def load(folder: str | Path) -> dict[str, Any]:
    """The record of the run stored in ``folder``, validated; DamagedResult if it is not whole."""
    path = Path(folder) / RESULT_FILE
    record = consistent(folder)
    if CHECKSUM not in record:
        raise DamagedResult(path, "has no checksum: every record carries one, so it was deleted and the "
                                  "record may have been edited; if you trust it, seal it with "
                                  f"`python -m mediated_transfer.stored.seal {Path(folder)}`")
    if record[CHECKSUM] != checksum(record):
        raise DamagedResult(path, "its content differs from the checksum recorded when the run was "
                                  "written: edited or damaged since")
    return decode({k: v for k, v in record.items() if k != CHECKSUM})


def consistent(folder: str | Path) -> dict[str, Any]:
    """result.json's raw record in ``folder`` if it is whole and consistent with itself and
    curve.csv, its checksum not yet judged; DamagedResult otherwise."""
    folder = Path(folder)
    path = folder / RESULT_FILE
    record = _parse(path)
    # The most telling problem first: what is wrong, then that it differs from what was written.
    for check in (_keys, _kinds, _consistency):
        problem = check(record)
        if problem:
            raise DamagedResult(path, problem)
    _check_curve(folder / CURVE_FILE, record)
    return record


def check_place(folder: str | Path, held: Any, cell: str, seed: int | str) -> None:
    """DamagedResult when ``folder``, the folder of table cell ``cell`` and seed ``seed``, holds
    the run of another cell or seed (``held``: its RunResult), moved or copied there: whole as it
    may be, it is not this folder's run. Like a damaged run, a sweep sets it aside and computes
    the folder's run, and a report leaves it out, naming it."""
    run = f"{held.strategy}_{held.n_source}", str(held.seed)
    if run != (str(cell), str(seed)):
        raise DamagedResult(Path(folder) / RESULT_FILE, f"holds the run {run[0]} seed={run[1]}, not this "
                                                        f"folder's {cell} seed={seed}: moved or copied here")


def _parse(path: Path) -> dict[str, Any]:
    if not path.is_file():
        what = "a folder" if path.is_dir() else "missing" if not path.exists() else "not a regular file"
        raise DamagedResult(path, f"is {what}, not a run's record")
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise DamagedResult(path, f"cannot be read ({error.strerror})") from None
    if not raw.strip():
        raise DamagedResult(path, "is empty")
    try:
        record = json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as error:
        raise DamagedResult(path, f"is not UTF-8 text (byte {error.start})") from None
    except json.JSONDecodeError as error:
        raise DamagedResult(path, f"is not valid JSON, cut short or damaged ({error.msg} at line "
                                  f"{error.lineno} column {error.colno})") from None
    if not isinstance(record, dict):
        raise DamagedResult(path, f"holds a JSON {_json_type(record)}, not a run's record (an object)")
    return record


def _keys(record: dict) -> str | None:
    missing = sorted(set(FIELDS) - OPTIONAL - set(record))
    if missing:
        return f"lacks the key(s) {', '.join(missing)}"
    unknown = sorted(set(record) - set(FIELDS) - {CHECKSUM})
    if unknown:
        return f"has unknown key(s) {', '.join(map(repr, unknown))}; allowed: {', '.join(FIELDS)}"
    return None


def _kinds(record: dict) -> str | None:
    for key, kind in FIELDS.items():
        if key in record and not _KINDS[kind](record[key]):
            return f"{key} must be {_DESCRIPTIONS[kind]}, got {_short(record[key])}"
    return None


def _consistency(record: dict) -> str | None:
    steps, rewards, rates = record["steps"], record["mean_reward"], record["success_rate"]
    if not len(steps) == len(rewards) == len(rates):
        return (f"steps, mean_reward and success_rate have {len(steps)}, {len(rewards)} and "
                f"{len(rates)} points")
    config = record.get("config") or {}
    best = _setting(config, "env", "success_reward", DEFAULT_SUCCESS_REWARD)
    slack = _TOLERANCE * max(1.0, best)
    outside = [r for r in rewards if not -slack <= r <= best + slack]
    if outside:
        return f"mean_reward must lie in [0, env.success_reward={best:g}], got {outside[0]!r}"
    failed = record.get("failure") is not None
    problem = _evaluation_points(record, config, failed)
    if problem or failed:  # a failed run's curve stops early and has no L_R or time: nothing to match
        return problem
    if record["reward_loss"] is None:
        return "reward_loss is null, but the run did not fail (failure is null)"
    loss = sum(best - r for r in rewards)
    if abs(record["reward_loss"] - loss) > _TOLERANCE * max(1.0, abs(loss)):
        return f"reward_loss {record['reward_loss']!r} is not that of its mean_reward ({loss:.6g})"
    threshold = _setting(config, None, "threshold", None)
    if threshold is not None and steps:
        from ..metrics import time_to_threshold

        reached = time_to_threshold(steps, rewards, threshold)
        if reached != record["time_to_threshold"]:
            return (f"time_to_threshold {record['time_to_threshold']!r} is not that of its mean_reward "
                    f"at threshold={threshold:g} ({reached!r})")
    return None


def _evaluation_points(record: dict, config: dict, failed: bool) -> str | None:
    """The curve's steps are its config's evaluation points (a failed run's: the first of them)."""
    steps, budget = record["steps"], record["budget"]
    if steps and steps[-1] > budget:
        return f"steps go beyond its budget of {budget} (last step {steps[-1]})"
    scale = config.get("scale") if isinstance(config.get("scale"), dict) else {}
    points, configured = scale.get("eval_points"), scale.get("budget")
    if _KINDS["positive"](configured) and configured != budget:
        return f"budget {budget} differs from its config's scale.budget={configured}"
    if not _KINDS["positive"](points) or budget % points:
        return None  # an older or partial config: nothing to compare with
    grid = [budget // points * i for i in range(1, points + 1)]
    if steps != grid[:len(steps)] or (not failed and len(steps) != points):
        return (f"its curve has {len(steps)} points at steps {_short(steps)}, but its config's "
                f"scale.eval_points={points} are steps {_short(grid)}")
    return None


def _check_curve(path: Path, record: dict) -> None:
    """curve.csv must hold exactly result.json's curve."""
    if not path.is_file():
        raise DamagedResult(path, "is missing" if not path.exists() else "is not a file")
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        raise DamagedResult(path, "cannot be read as text") from None
    if not lines or lines[0].strip() != CURVE_HEADER:
        raise DamagedResult(path, f"does not start with its header {CURVE_HEADER}")
    stored = list(zip(record["steps"], record["mean_reward"], record["success_rate"]))
    rows = []
    for number, line in enumerate(lines[1:], start=2):
        parts = line.split(",")
        try:
            if len(parts) != 3:
                raise ValueError(line)
            rows.append((int(parts[0]), float(parts[1]), float(parts[2])))
        except ValueError:
            raise DamagedResult(path, f"line {number} is not {CURVE_HEADER}: {_short(line)}") from None
    if len(rows) != len(stored):
        raise DamagedResult(path, f"has {len(rows)} points, {RESULT_FILE} {len(stored)}: cut short or "
                                  "not this run's")
    for row, want in zip(rows, stored):
        if row != tuple(want):
            raise DamagedResult(path, f"step,mean_reward,success_rate {row[0]},{row[1]!r},{row[2]!r}, but "
                                      f"{RESULT_FILE} has {want[0]},{want[1]!r},{want[2]!r}")


def _setting(config: dict, section: str | None, key: str, default):
    node = config.get(section) if section else config
    value = node.get(key) if isinstance(node, dict) else None
    return float(value) if _is_number(value) and math.isfinite(value) else default


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _finite(value: Any) -> bool:
    return _is_number(value) and math.isfinite(value)


_KINDS = {
    "name": lambda v: isinstance(v, str) and v != "",
    "count": lambda v: _is_int(v) and v >= 0,
    "positive": lambda v: _is_int(v) and v >= 1,
    "steps": lambda v: isinstance(v, list) and all(_is_int(s) and s >= 1 for s in v)
    and all(a < b for a, b in zip(v, v[1:])),
    "numbers": lambda v: isinstance(v, list) and all(_finite(x) for x in v),
    "rates": lambda v: isinstance(v, list) and all(_finite(x) and 0 <= x <= 1 for x in v),
    "number or null": lambda v: v is None or _finite(v),
    "step or null": lambda v: v is None or (_is_int(v) and v >= 0),
    "seconds": lambda v: _finite(v) and v >= 0,
    "speed or null": lambda v: v is None or (_finite(v) and v >= 0),  # null: too fast to time
    "mapping": lambda v: isinstance(v, dict),
    "mapping or null": lambda v: v is None or isinstance(v, dict),
    "count or null": lambda v: v is None or (_is_int(v) and v >= 0),
    "text or null": lambda v: v is None or isinstance(v, str),
}
_DESCRIPTIONS = {
    "name": "a non-empty string",
    "count": "an integer >= 0",
    "positive": "an integer >= 1",
    "steps": "a list of increasing integers >= 1",
    "numbers": "a list of finite numbers",
    "rates": "a list of finite numbers in [0, 1]",
    "number or null": "a finite number or null",
    "step or null": "an integer >= 0 or null",
    "seconds": "a finite number >= 0",
    "speed or null": "a finite number >= 0 or null",
    "mapping": "an object",
    "mapping or null": "an object or null",
    "count or null": "an integer >= 0 or null",
    "text or null": "a string or null",
}


def _json_type(value: Any) -> str:
    return {list: "array", str: "string", bool: "boolean", type(None): "null"}.get(type(value), "number")


def _short(value: Any, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."
