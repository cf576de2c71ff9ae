"""Where the config tree is, for every module that reads it (compose, tuned, worlds, help)."""

from __future__ import annotations

from pathlib import Path

CONF_DIR = Path(__file__).resolve().parents[3] / "conf"
"""The config tree; it sits next to src/ (the package is installed in editable mode)."""
CONFIG_NAME = "config"
