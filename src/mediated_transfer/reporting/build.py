"""Build the report of one experiment (a table sweep) from its run outputs.

From the composed config of the experiment (the same conf/ that ran the sweep: paths, scale,
learner, report, and the variant: Hydra's override_dirname) this reads the finished runs of that
variant, summarises each table cell, writes the table (md, csv, tex) and the figure, and logs one
MLflow summary run per cell with the table and figure as artifacts. The baseline's report goes to
paths.reports_dir, a variant's to paths.reports_dir/variants/<variant>/. Nothing is typed in:
every measured number comes from result.json files.
"""

from __future__ import annotations

import hashlib
import re
import shlex
import sys
from dataclasses import dataclass, field
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from ..metrics import MetricsConfig
from ..provenance.judge import stale
from ..sweep import tracking
from .collect import CellRuns, collect_sweep, runs_per_variant, variant_label
from .collect import summaries as cell_summaries
from .compose import ReportError, variant_of
from .figures import Curve, cell_label, fastest_transfer, plot_curves
from .paper import paper_rows
from .tables import TableHeader, table_rows, write_tables


class NoRuns(FileNotFoundError):
    """No finished run of the requested variant in the sweep folder."""


@dataclass
class Report:
    name: str
    tables: list[Path]
    figure: Path | None
    runs: int
    variant: str = ""
    summary_runs: list[str] = field(default_factory=list)
    stale: list[str] = field(default_factory=list)
    """One line per run computed by other code than the current (provenance/judge.py)."""
    left_out: list[str] = field(default_factory=list)
    """One line per damaged run left out of the tables (its file, what is wrong)."""

    def line(self) -> str:
        """What was built, in one line: experiment, variant, runs, files."""
        files = [*map(str, self.tables), *([str(self.figure)] if self.figure else [])]
        what = f"{self.name} [{self.variant}]" if self.variant else self.name
        notes = [f"{len(self.stale)} stale"] if self.stale else []
        notes += [f"{len(self.left_out)} damaged left out"] if self.left_out else []
        notes_text = f" ({', '.join(notes)})" if notes else ""
        return f"{what}: {self.runs} run{'' if self.runs == 1 else 's'}{notes_text} -> {', '.join(files)}"


def build_report(cfg: DictConfig) -> Report:
    """Tables, figure and MLflow summaries of the experiment ``cfg`` (needs ``cfg.report``).

    The variant is ``cfg.hydra.job.override_dirname`` (compose with return_hydra_config=True);
    a config without Hydra's part is reported as the baseline.
    """
    if cfg.get("report") is None:
        # ReportError: `reporting` without experiment names skips it (e.g. experiment=sensitivity,
        # whose report is its own command).
        raise ReportError(f"experiment {cfg.name} has no table report section: "
                          f"conf/experiment/{cfg.name}.yaml says how it is reported")
    variant = variant_of(cfg)
    left_out: list[str] = []
    cells = finished_runs(cfg, left_out)
    metrics_cfg = MetricsConfig(max_reward=float(cfg.env.success_reward), threshold=float(cfg.threshold))
    summaries = cell_summaries(cells, metrics_cfg)
    strategies = {name: (c.strategy, c.n_source) for name, c in cells.items()}
    stale_lines = [f"{name} seed={r.seed}: {why}" for name, c in cells.items() for r in c.results
                   if (why := stale(r)) is not None]

    header = TableHeader(
        title=str(cfg.report.title), scale=str(cfg.scale.name), budget=int(cfg.scale.budget),
        eval_points=int(cfg.scale.eval_points), eval_episodes=int(cfg.scale.eval_episodes),
        runs_per_row=int(cfg.scale.seeds), threshold=metrics_cfg.threshold,
        max_reward=metrics_cfg.max_reward, variant=variant, stale_runs=len(stale_lines), left_out_runs=len(left_out))
    failed = {name: len(c.failed) for name, c in cells.items() if c.failed}
    rows = table_rows(summaries, strategies, paper_rows(cfg.report.paper_table), header.runs_per_row,
                      failed)
    out_dir = reports_dir(cfg, variant)
    tables = write_tables(rows, header, out_dir, str(cfg.name))

    curves = []
    for cell in ("none_0", fastest_transfer(summaries, strategies)):
        if cell in summaries:
            curves.append(Curve(cell_label(*strategies[cell], summaries[cell]["n_runs"]), summaries[cell]))
    figure = None
    if curves:
        title = str(cfg.report.figure_title) + (f", variant {variant}" if variant else "")
        subtitle = (f"scale {header.scale}: {header.budget:,} steps, mean of runs +/- SEM; "
                    "fastest: first to reach the threshold, then lowest L_R")
        figure = plot_curves(curves, header.threshold, header.max_reward, title, subtitle,
                             out_dir / f"{cfg.report.figure}.png")
    report = Report(str(cfg.name), tables, figure, sum(len(c.results) for c in cells.values()), variant,
                    stale=stale_lines, left_out=left_out)
    if cfg.tracking.enabled:
        report.summary_runs = _log_summaries(cfg, variant, cells, summaries, tables + ([figure] if figure else []))
    return report


def finished_runs(cfg: DictConfig, left_out: list[str] | None = None) -> dict[str, CellRuns]:
    """The finished runs of the variant of ``cfg`` by table cell; NoRuns (saying which variants
    do have runs, and the command that runs this one) when there are none. Damaged runs are
    left out, one line each in ``left_out`` (collect.collect_sweep)."""
    variant = variant_of(cfg)
    sweep_dir = Path(cfg.paths.sweep_dir)
    damaged: list[str] = []
    cells = collect_sweep(sweep_dir, cfg.algorithm.name, cfg.representation.name, int(cfg.scale.budget),
                          int(cfg.scale.eval_points), variant, int(cfg.scale.eval_episodes), damaged)
    if left_out is None:  # the caller keeps no list: they are named here
        for line in damaged:
            print(f"left out: {line}", file=sys.stderr)
    else:
        left_out += damaged
    if cells:
        return cells
    present = runs_per_variant(sweep_dir)
    there = ", ".join(f"{variant_label(v)} ({n} run{'' if n == 1 else 's'})" for v, n in present.items())
    what = f"the variant {variant}" if variant else "the baseline"
    also = f"; {len(damaged)} damaged, e.g. {damaged[0]}" if damaged else ""
    raise NoRuns(f"no runs of {what} in {sweep_dir} (runs there: {there or 'none'}{also}); "
                 f"run the sweep first: {sweep_command(cfg)}")


def sweep_command(cfg: DictConfig) -> str:
    """The command that runs the sweep of ``cfg``: its overrides as given (when known)."""
    overrides = OmegaConf.select(cfg, "hydra.overrides.task")
    if overrides is None:
        return f"python -m mediated_transfer experiment={cfg.name} scale={cfg.scale.name}"
    # Numeric group choices were quoted for Hydra (n_source='15'); the entry point takes them bare.
    return shlex.join(["python", "-m", "mediated_transfer", *(re.sub(r"'(\d+)'", r"\1", a) for a in overrides)])


def reports_dir(cfg: DictConfig, variant: str) -> Path:
    """paths.reports_dir for the baseline; its variants/<variant>/ for a variant."""
    root = Path(cfg.paths.reports_dir)
    return root / "variants" / path_name(variant) if variant else root


def path_name(text: str, limit: int = 120) -> str:
    """``text`` as one file or folder name of at most ``limit`` characters: characters other than
    letters, digits and . _ = , + - become '_' (a variant may hold '/', quotes or brackets)."""
    name = re.sub(r"[^\w.=,+-]", "_", text, flags=re.ASCII)
    if len(name) > limit:  # file systems limit names to 255 bytes; keep them distinct when cut
        name = f"{name[:limit - 20]}-{hashlib.sha256(text.encode()).hexdigest()[:12]}"
    return name


def _log_summaries(cfg: DictConfig, variant: str, cells, summaries, artifacts: list[Path]) -> list[str]:
    settings = tracking.TrackingSettings.from_config(cfg.tracking)
    sweep = f"{cfg.name}/{cfg.scale.name}"
    label = variant_label(variant)
    # The summaries depend on every run of the table (the artifacts show them all) and on the
    # variant they describe.
    digest = hashlib.sha256(f"variant={variant};".encode())
    for name in sorted(cells):
        for r in cells[name].results:
            digest.update(f"{name}/{r.seed}:{r.reward_loss!r}:{r.mean_reward!r};".encode())
        for r in cells[name].failed:
            digest.update(f"{name}/{r.seed}:failed;".encode())
    fingerprint = digest.hexdigest()[:32]
    ids = []
    for name in summaries:  # a cell whose every run failed has no summary to log
        cell = cells[name]
        tags = {"table": str(cfg.name), "cell": name, "sweep": sweep, "scale": str(cfg.scale.name),
                "variant": label, "strategy": cell.strategy, "n_source": str(cell.n_source),
                "seeds": ",".join(str(s) for s in cell.seeds), "failed_runs": str(len(cell.failed))}
        # The baseline keeps the key it always had, so its existing summaries are updated in place.
        key = f"summary/{sweep}/{name}" + (f"/{variant}" if variant else "")
        ids.append(tracking.log_summary(
            settings, str(cfg.name), key=key, run_name=f"{name} (summary, {label})",
            summary=summaries[name], tags=tags, artifacts=artifacts, fingerprint=fingerprint))
    return ids
