"""Build the report of one experiment (a table sweep) from its run outputs.

From the composed config of the experiment (the same conf/ that ran the sweep: paths, scale,
learner, report) this reads the finished runs, summarises each cell, writes the table (md, csv,
tex) and the figure, and logs one MLflow summary run per cell with the table and figure as
artifacts. Nothing is typed in: every measured number comes from result.json files.
"""

from __future__ import annotations

import hashlib
import logging
from dataclasses import dataclass, field
from pathlib import Path

from omegaconf import DictConfig

from .. import tracking
from ..metrics import MetricsConfig
from .collect import collect_sweep
from .figures import Curve, cell_label, fastest_transfer, plot_curves
from .paper import paper_rows
from .tables import TableHeader, table_rows, write_tables

log = logging.getLogger(__name__)


@dataclass
class Report:
    name: str
    tables: list[Path]
    figure: Path | None
    runs: int
    summary_runs: list[str] = field(default_factory=list)


def build_report(cfg: DictConfig) -> Report:
    """Tables, figure and MLflow summaries of the experiment ``cfg`` (needs ``cfg.report``)."""
    if cfg.get("report") is None:
        raise ValueError(f"the config '{cfg.name}' has no report section; build reports of an "
                         "experiment, e.g. experiment=table2_rbf")
    sweep_dir = Path(cfg.paths.sweep_dir)
    cells = collect_sweep(sweep_dir, cfg.algorithm.name, cfg.representation.name, int(cfg.scale.budget),
                          int(cfg.scale.eval_points))
    if not cells:
        raise FileNotFoundError(
            f"no finished runs in {sweep_dir}; run the sweep first: "
            f"python -m mediated_transfer experiment={cfg.name} scale={cfg.scale.name}")
    metrics_cfg = MetricsConfig(max_reward=float(cfg.env.success_reward), threshold=float(cfg.threshold))
    summaries = {name: c.summary(metrics_cfg) for name, c in cells.items()}
    strategies = {name: (c.strategy, c.n_source) for name, c in cells.items()}

    header = TableHeader(
        title=str(cfg.report.title), scale=str(cfg.scale.name), budget=int(cfg.scale.budget),
        eval_points=int(cfg.scale.eval_points), eval_episodes=int(cfg.scale.eval_episodes),
        runs_per_row=int(cfg.scale.seeds), threshold=metrics_cfg.threshold,
        max_reward=metrics_cfg.max_reward)
    rows = table_rows(summaries, strategies, paper_rows(str(cfg.report.paper_table)), header.runs_per_row)
    out_dir = Path(cfg.paths.reports_dir)
    tables = write_tables(rows, header, out_dir, str(cfg.name))

    curves = []
    for cell in ("none_0", fastest_transfer(summaries, strategies)):
        if cell in summaries:
            curves.append(Curve(cell_label(*strategies[cell], summaries[cell]["n_runs"]), summaries[cell]))
    figure = None
    if curves:
        subtitle = (f"scale {header.scale}: {header.budget:,} steps, mean of runs +/- SEM; "
                    "fastest: first to reach the threshold, then lowest L_R")
        figure = plot_curves(curves, header.threshold, header.max_reward, str(cfg.report.figure_title),
                             subtitle, out_dir / f"{cfg.report.figure}.png")
    report = Report(str(cfg.name), tables, figure, sum(len(c.results) for c in cells.values()))
    if cfg.tracking.enabled:
        report.summary_runs = _log_summaries(cfg, cells, summaries, tables + ([figure] if figure else []))
    log.info("%s: %d runs -> %s%s", report.name, report.runs, ", ".join(str(t) for t in tables),
             f", {figure}" if figure else "")
    return report


def _log_summaries(cfg: DictConfig, cells, summaries, artifacts: list[Path]) -> list[str]:
    settings = tracking.TrackingSettings.from_config(cfg.tracking)
    sweep = f"{cfg.name}/{cfg.scale.name}"
    # The summaries depend on every run of the table (the artifacts show them all).
    digest = hashlib.sha256()
    for name in sorted(cells):
        for r in cells[name].results:
            digest.update(f"{name}/{r.seed}:{r.reward_loss!r}:{r.mean_reward!r};".encode())
    fingerprint = digest.hexdigest()[:32]
    ids = []
    for name, cell in cells.items():
        tags = {"table": str(cfg.name), "cell": name, "sweep": sweep, "scale": str(cfg.scale.name),
                "strategy": cell.strategy, "n_source": str(cell.n_source),
                "seeds": ",".join(str(s) for s in cell.seeds)}
        ids.append(tracking.log_summary(
            settings, str(cfg.name), key=f"summary/{sweep}/{name}", run_name=f"{name} (summary)",
            summary=summaries[name], tags=tags, artifacts=artifacts, fingerprint=fingerprint))
    return ids
