"""The tests' optional dependencies: the package's ``deep`` extra (torch, Stable-Baselines3),
which the DQN, the SB3 learners and the lockstep runs need and the linear learners do not.

Where it is not installed (``make test-no-torch``, as CI runs it on Python 3.12 and 3.13), the
tests that need it skip: a test module that imports torch (``importorskip``), a test marked
``needs_deep``, and a test parametrized with a deep learner's option (``DEEP_OPTIONS``, applied
by conftest.py). ``make test`` installs everything and sets ``REQUIRE_DEEP=1``: there a missing
package fails those tests instead.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from types import ModuleType
from typing import Any

import pytest

REQUIRED = os.environ.get("REQUIRE_DEEP") == "1"
HINT = "pip install 'mediated-transfer[deep]' (make install does)"


def installed(name: str) -> bool:
    return importlib.util.find_spec(name) is not None


DEEP = REQUIRED or (installed("torch") and installed("stable_baselines3"))
"""Whether the deep learners can run here."""
REASON = f"needs the deep extra (torch, Stable-Baselines3): {HINT}"
DEEP_OPTIONS = frozenset({"dqn", "sb3_ppo", "sb3_dqn", "network", "dqn_network", "table4_dnn"})
"""Config options (algorithm, representation, tuned, experiment) that build a deep learner."""

needs_deep = pytest.mark.skipif(not DEEP, reason=REASON)
"""Marks a test (or a parameter) that needs the deep extra, in a module whose other tests do not."""


def importorskip(name: str) -> ModuleType:
    """The module ``name``; without it the calling test module skips (fails with REQUIRE_DEEP=1)."""
    if REQUIRED or installed(name):
        return importlib.import_module(name)
    pytest.skip(f"needs {name}: {HINT}", allow_module_level=True)


def deep_option(value: Any) -> bool:
    """Whether a test parameter names a deep learner's option: ``dqn``, ``algorithm=dqn``, ..."""
    return isinstance(value, str) and value.split("=")[-1] in DEEP_OPTIONS
