"""The tests' optional dependencies: torch and Stable-Baselines3 (the package's ``deep`` extra).

Where they are not installed (``make test-no-torch``, as CI runs it on Python 3.12 and 3.13),
the tests that need them skip. ``make test`` installs everything and sets ``REQUIRE_DEEP=1``:
there a missing one fails those tests instead of skipping them.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from types import ModuleType

import pytest

REQUIRED = os.environ.get("REQUIRE_DEEP") == "1"
HINT = "pip install 'mediated-transfer[deep]' (make install does)"


def installed(name: str) -> bool:
    return importlib.util.find_spec(name) is not None


def importorskip(name: str) -> ModuleType:
    """The module ``name``; without it, the calling test module skips (fails with REQUIRE_DEEP=1)."""
    if REQUIRED or installed(name):
        return importlib.import_module(name)
    pytest.skip(f"needs {name}: {HINT}", allow_module_level=True)


needs_torch = pytest.mark.skipif(not (REQUIRED or installed("torch")), reason=f"needs torch: {HINT}")
"""Marks a test (or a parameter) that needs torch, in a module whose other tests do not."""
