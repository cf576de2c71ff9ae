"""Who a run is, in folders and in MLflow: its table cell, seed, variant and run key.

A variant is every override of a run besides its table cell, seed and where outputs go (the
keys conf/config.yaml excludes from ``hydra.job.override_dirname``), e.g.
``algorithm.lambda_=0.5``; '' is the baseline. Hydra puts a variant's runs one folder deeper
(``<cell>/seed=<k>/<variant>/``); the same string names its MLflow runs and its reports, so a
variant is never mixed with or mistaken for the baseline.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from omegaconf import DictConfig

from ..config.spec import spec_digest

if TYPE_CHECKING:
    from ..run import RunSpec

BASELINE_TAG = "baseline"
"""The variant tag of runs with no overrides beyond cell and seed."""


def variant_label(variant: str) -> str:
    return variant or BASELINE_TAG


def run_label(cfg: DictConfig, variant: str) -> str:
    """A run as its progress lines and errors name it: ``regular_50 seed=3`` (``[variant]``)."""
    return f"{cfg.cell} seed={cfg.seed}" + (f" [{variant}]" if variant else "")


def run_name(cfg: DictConfig, variant: str) -> str:
    """MLflow run name: ``regular_50/seed=3``, and ``[algorithm.lambda_=0.5]`` for a variant."""
    name = f"{cfg.cell}/seed={cfg.seed}"
    return f"{name} [{variant}]" if variant else name


def run_tags(cfg: DictConfig, folder: Path, spec: "RunSpec", variant: str, code_digest: str) -> dict[str, str]:
    """MLflow tags of a run: table, cell, sweep, scale, seed, variant and the run key.

    The run key is the run's folder relative to paths.root plus a digest of what the run
    computes and of the code that computed it: the same run always has the same key, which is
    how re-running a sweep avoids duplicate MLflow runs; another config in the same folder, or
    the same run recomputed by other code, gets another key.
    """
    where = run_where(cfg.paths.root, folder)
    return {
        "table": str(cfg.name),
        "cell": str(cfg.cell),
        "sweep": f"{cfg.name}/{cfg.scale.name}",
        "scale": str(cfg.scale.name),
        "seed": str(cfg.seed),
        "strategy": str(cfg.strategy.name),
        "n_source": str(cfg.n_source),
        "variant": variant_label(variant),
        "run_key": f"{where}@{spec_digest(spec)}.{code_digest}",
    }


def run_where(root: str | Path, folder: str | Path) -> str:
    """A run's folder as its run key begins: relative to paths.root (absolute if outside it)."""
    root, path = Path(root).resolve(), Path(folder).resolve()
    return path.relative_to(root).as_posix() if path.is_relative_to(root) else path.as_posix()
