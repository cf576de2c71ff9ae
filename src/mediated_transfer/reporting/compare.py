"""``python -m mediated_transfer.reporting.compare experiment=table2_rbf [scale=smoke] [overrides]
--variant "algorithm.lambda_=0.5" [--variant "..." ...] [--no-baseline] [--seeds 0-9]``

Compares sweeps of one experiment side by side: the baseline (the experiment with the shared
overrides) first, unless --no-baseline, then each --variant (space-separated Hydra overrides,
added to the shared ones). Writes one table (Markdown, CSV) with a row per table cell and, per
sweep, its runs, reward loss L_R, time to threshold and discovery / learning split, and each
sweep's L_R minus the first's; and one figure, L_R per table cell with a bar per sweep; to
<paths.reports_dir>/compare/<experiment>__<first>__vs__<second>[__vs__...].{md,csv,png}.
With --seeds, every sweep counts only its runs of those seeds (e.g. a variant run on seeds 0-9
against a baseline of 20), so the sweeps are compared on the same seeds; the files' names end
in ``__seeds_<first>-<last>``.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from omegaconf import DictConfig

from ..metrics import MetricsConfig
from .build import finished_runs, path_name
from .collect import summaries as cell_summaries
from .collect import variant_label
from .comparison import Split, Sweep, compared_cells, numbers, preamble, reward_loss_bars, shown
from .compose import (USER_ERRORS, ReportError, compose_experiment, experiment_names, one_line,
                      split_experiments, variant_of)
from .figures import plot_loss_bars
from .formats import write_csv, write_markdown
from .paper import paper_rows, scheme

USAGE = __doc__


@dataclass
class Comparison:
    files: list[Path]
    sweeps: list[Sweep]

    def line(self) -> str:
        what = " vs ".join(f"{s.label} ({s.runs} run{'' if s.runs == 1 else 's'})" for s in self.sweeps)
        return f"{what} -> {', '.join(map(str, self.files))}"


def compare(experiment: str, shared: Sequence[str], variants: Sequence[str], baseline: bool = True,
            seeds: Sequence[int] | None = None) -> Comparison:
    """Table and figure of the sweeps of ``experiment``: the baseline (unless not ``baseline``),
    then each of ``variants`` (space-separated overrides), all with the ``shared`` overrides;
    with ``seeds``, of the runs of those seeds only."""
    configs = ([compose_experiment(experiment, shared)] if baseline else []) + [
        compose_experiment(experiment, [*shared, *_overrides(v)]) for v in variants]
    if len(configs) < 2:
        raise ReportError("--variant: a comparison needs two sweeps at least (the baseline and a "
                          "--variant, or two --variant without --no-baseline)")
    names = [variant_of(cfg) for cfg in configs]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ReportError(f"--variant {variants[i - int(baseline)]!r}: the same sweep as "
                              f"{variant_label(name)!r} (Hydra names both {name!r}); compare different sweeps")
    sweeps = [_sweep(cfg, seeds) for cfg in configs]

    first = configs[0]
    table = str(first.name)
    cells = compared_cells(sweeps, paper_rows(first.report.paper_table))
    out = Path(first.paths.reports_dir) / "compare"
    out.mkdir(parents=True, exist_ok=True)
    stem = comparison_stem(table, [s.label for s in sweeps], seeds)
    title = str(first.report.title)
    notes = preamble(table, title, str(first.scale.name), float(first.threshold),
                     float(first.env.success_reward), sweeps)
    texts = shown(sweeps, cells)
    files = [
        write_markdown(texts, out / f"{stem}.md", notes, ["left"] + ["right"] * (len(texts.columns) - 1)),
        write_csv(numbers(sweeps, cells), out / f"{stem}.csv"),
    ]
    labels = [scheme(s) if s == "none" else f"{s} {n}" for s, n in cells]
    files.append(plot_loss_bars(labels, reward_loss_bars(sweeps, cells), f"{title}: reward loss per table cell",
                                f"scale {first.scale.name}: " + " vs ".join(s.label for s in sweeps)
                                + "; mean of runs +/- SEM, lower is better", out / f"{stem}.png"))
    return Comparison(files, sweeps)


def comparison_stem(table: str, labels: Sequence[str], seeds: Sequence[int] | None = None) -> str:
    """File name (without extension) of a comparison: the table, the sweeps, the seeds; at most
    240 characters, so many long variants still make a valid name (cut with a hash, distinct)."""
    stem = f"{path_name(table)}__" + "__vs__".join(path_name(label) for label in labels) + (
        "" if seeds is None else f"__seeds_{_seeds_text(seeds)}")
    return path_name(stem, limit=240)


def _overrides(variant: str) -> list[str]:
    try:
        return shlex.split(variant)
    except ValueError as error:  # an unbalanced quote
        raise ReportError(f"--variant {variant!r}: {error}; give space-separated overrides") from None


def _sweep(cfg: DictConfig, seeds: Sequence[int] | None) -> Sweep:
    cells = finished_runs(cfg)
    if seeds is not None:
        for cell in cells.values():
            cell.results = [r for r in cell.results if r.seed in seeds]
        cells = {name: c for name, c in cells.items() if c.results}
        if not cells:
            raise ReportError(f"--seeds {_seeds_text(seeds)}: {variant_label(variant_of(cfg))} has no "
                              "finished run of these seeds")
    threshold = float(cfg.threshold)
    metrics = MetricsConfig(max_reward=float(cfg.env.success_reward), threshold=threshold)
    return Sweep(variant_of(cfg), cell_summaries(cells, metrics),
                 {name: (c.strategy, c.n_source) for name, c in cells.items()},
                 int(cfg.scale.seeds) if seeds is None else len(seeds),
                 int(cfg.scale.budget), int(cfg.scale.eval_points),
                 {name: Split.of(c, threshold, metrics.max_reward) for name, c in cells.items() if c.results})


def parse_seeds(text: str) -> list[int]:
    """``0-9`` or ``0,3,5``: the seeds; a one-line error otherwise."""
    try:
        if "-" in text:
            first, last = (int(x) for x in text.split("-", 1))
            seeds = list(range(first, last + 1))
        else:
            seeds = [int(x) for x in text.split(",")]
    except ValueError:
        seeds = []
    if not seeds or min(seeds) < 0:
        raise ReportError(f"--seeds {text!r}: give a range like 0-9 or a list like 0,3,5 of seeds >= 0")
    return sorted(set(seeds))


def _seeds_text(seeds: Sequence[int]) -> str:
    contiguous = len(seeds) > 1 and list(seeds) == list(range(seeds[0], seeds[-1] + 1))
    return f"{seeds[0]}-{seeds[-1]}" if contiguous else ",".join(map(str, seeds))


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line and exit code 1, as every reporting error
        raise SystemExit(f"error: {message}; usage: python -m mediated_transfer.reporting.compare "
                         "experiment=<table> [overrides] --variant \"<overrides>\" [--no-baseline]")


def main(argv: Sequence[str] | None = None) -> int:
    parser = _Parser(prog="python -m mediated_transfer.reporting.compare", description=USAGE,
                     formatter_class=argparse.RawDescriptionHelpFormatter, add_help=True)
    parser.add_argument("overrides", nargs="*", help="experiment=<table> and overrides shared by all sweeps")
    parser.add_argument("--variant", action="append", default=[], metavar="OVERRIDES",
                        help="a sweep to compare: space-separated overrides (repeatable)")
    parser.add_argument("--no-baseline", action="store_true", help="compare the variants only")
    parser.add_argument("--seeds", default=None, help="only the runs of these seeds: 0-9 or 0,3,5")
    args = parser.parse_intermixed_args(sys.argv[1:] if argv is None else list(argv))
    try:
        experiments, shared = split_experiments(args.overrides)
        if len(experiments) != 1:
            raise ReportError(f"experiment: name the one experiment to compare (got "
                              f"{', '.join(experiments) or 'none'}); allowed: {', '.join(experiment_names())}")
        seeds = None if args.seeds is None else parse_seeds(args.seeds)
        comparison = compare(experiments[0], shared, args.variant, not args.no_baseline, seeds)
    except USER_ERRORS as error:
        raise SystemExit(f"error: {one_line(error)}") from None
    print(f"{experiments[0]}: {comparison.line()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
