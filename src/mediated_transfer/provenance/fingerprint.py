"""A fingerprint of what runs computed: SHA-256 over their results and their trained learners'
state, bit for bit, and over nothing else.

Two runs with equal fingerprints computed the same numbers: the same curve, success rates,
reward loss, time to threshold, source phase, discovery step, episode choices and learner
statistics, and learners that end with the same weights (and optimizer moments, replay buffer,
generator state: whatever ``state_dict()`` holds). How long the runs took and which code
computed them are left out: a fingerprint compares the computations of two versions of the code.
"""

from __future__ import annotations

import hashlib
import struct
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

COMPUTED = ("steps", "mean_reward", "success_rate", "reward_loss", "time_to_threshold", "source_phase_end",
            "source_tasks_solved", "first_target_reward_step", "failure", "choices", "learner_stats")
"""The fields of a RunResult that a run computes (its wall time, speed, config and code are not)."""


def fingerprint(runs: Iterable[tuple[Any, Mapping[str, Any]]], leave_out: Iterable[str] = ()) -> str:
    """64 hex digits over ``runs``: (RunResult, its learner's ``state_dict()``) pairs, in order.
    ``leave_out``: fields of COMPUTED fed as None, as a run that did not record them had them
    (a fingerprint taken then is reproduced exactly; carry_over.py, ``choices``)."""
    leave_out = frozenset(leave_out)
    unknown = leave_out - set(COMPUTED)
    if unknown:
        raise ValueError(f"cannot leave out {sorted(unknown)}: not computed fields ({', '.join(COMPUTED)})")
    digest = hashlib.sha256()
    for result, state in runs:
        _feed(digest, {key: None if key in leave_out else getattr(result, key) for key in COMPUTED})
        _feed(digest, state)
    return digest.hexdigest()


def _feed(digest, value: Any) -> None:
    """Feed ``value`` with a tag for its type, and lengths, so that no two values read alike
    (1 and 1.0 and "1", [a, b] and [ab])."""
    if value is None:
        digest.update(b"N")
    elif isinstance(value, (bool, np.bool_)):
        digest.update(b"T" if value else b"F")
    elif isinstance(value, (int, np.integer)) and not isinstance(value, np.ndarray):
        _chunk(digest, b"I", str(int(value)).encode())
    elif isinstance(value, float):
        digest.update(b"D" + struct.pack("<d", value))  # every bit, -0.0 and the NaN's included
    elif isinstance(value, str):
        _chunk(digest, b"S", value.encode())
    elif isinstance(value, bytes):
        _chunk(digest, b"Y", value)
    elif isinstance(value, Mapping):
        digest.update(b"M%d;" % len(value))
        for key in sorted(value, key=str):
            _feed(digest, str(key))
            _feed(digest, value[key])
    elif isinstance(value, (list, tuple)):
        digest.update(b"L%d;" % len(value))
        for item in value:
            _feed(digest, item)
    elif isinstance(value, (np.ndarray, np.generic)):
        array = np.ascontiguousarray(value)
        _chunk(digest, b"A", f"{array.dtype.str}{array.shape}".encode())
        _chunk(digest, b"", array.tobytes())
    elif type(value).__module__.startswith("torch") and hasattr(value, "detach"):
        # A tensor, read without importing torch here (a linear run never imports it): its
        # bytes as uint8, which every dtype (bfloat16 too) can be viewed as.
        tensor = value.detach().cpu().contiguous()
        _chunk(digest, b"A", f"{tensor.dtype}{tuple(tensor.shape)}".encode())
        _chunk(digest, b"", tensor.reshape(-1).view(_uint8(tensor)).numpy().tobytes())
    else:
        raise TypeError(f"cannot fingerprint a {type(value).__module__}.{type(value).__qualname__}")


def _chunk(digest, tag: bytes, data: bytes) -> None:
    digest.update(tag + b"%d:" % len(data))
    digest.update(data)


def _uint8(tensor):
    import torch  # only reached with a tensor in hand

    return torch.uint8
