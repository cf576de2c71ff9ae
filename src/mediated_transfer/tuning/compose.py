"""The project's config for a list of overrides, composed with Hydra's compose API."""

from __future__ import annotations

from collections.abc import Sequence

from hydra import compose, initialize_config_dir
from omegaconf import DictConfig

from ..app import CONF_DIR, CONFIG_NAME, quote_numeric_choices


def compose_config(overrides: Sequence[str]) -> DictConfig:
    """conf/config.yaml with ``overrides`` applied, as ``python -m mediated_transfer`` would run it."""
    # A fresh Hydra context per call (restored on exit): workers and tests need no global setup.
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(CONFIG_NAME, overrides=quote_numeric_choices(list(overrides)))
