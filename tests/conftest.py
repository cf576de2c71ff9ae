"""Without the deep extra (torch, Stable-Baselines3), each test parametrized with a deep
learner's option skips, e.g. ``test_run.py::...[dqn-network]`` (tests/optional.py)."""

from __future__ import annotations

import pytest

from .optional import DEEP, REASON, deep_option


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    if DEEP:
        return
    for item in items:
        callspec = getattr(item, "callspec", None)
        if callspec is not None and any(deep_option(v) for v in callspec.params.values()):
            item.add_marker(pytest.mark.skip(reason=REASON))
