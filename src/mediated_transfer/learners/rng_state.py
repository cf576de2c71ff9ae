"""A learner's random generator state as plain integers, so that checkpoints hold only arrays or
tensors (nothing to unpickle) and a resumed run draws exactly what the original would have."""

from __future__ import annotations

import numpy as np

NUM_WORDS = 10
"""PCG64's 128-bit state and increment as 4 x 32-bit words each, then its cached half-draw flag
and value. 32-bit words fit both a uint64 array and an int64 tensor."""


def rng_state_words(rng: np.random.Generator) -> list[int]:
    state = rng.bit_generator.state
    if state["bit_generator"] != "PCG64":
        raise ValueError(f"only PCG64 generators can be saved, got {state['bit_generator']}")
    words = [(state["state"][k] >> (32 * j)) & 0xFFFFFFFF for k in ("state", "inc") for j in range(4)]
    return words + [int(state["has_uint32"]), int(state["uinteger"])]


def restore_rng_state(rng: np.random.Generator, words) -> None:
    """Put ``rng`` (a PCG64 generator) in the state ``rng_state_words`` returned."""
    words = [int(w) for w in np.asarray(words).reshape(-1).tolist()]
    if len(words) != NUM_WORDS:
        raise ValueError(f"a saved generator state holds {NUM_WORDS} words, got {len(words)}")

    def number(ws):
        return sum(w << (32 * j) for j, w in enumerate(ws))

    rng.bit_generator.state = {
        "bit_generator": "PCG64",
        "state": {"state": number(words[0:4]), "inc": number(words[4:8])},
        "has_uint32": words[8],
        "uinteger": words[9],
    }
