"""Table I rebuilt: ``python -m mediated_transfer.tuning.table1`` (``make table1``).

Reads the committed ``tuning/<learner>/trials.csv`` of every search space in
conf/hparams_search/ and writes ``reports/table1.md``: per learner the chosen values (the best
trial's), the search ranges and why, the trials and tuning seeds, the objective reached and the
provisional defaults' objective on the same seeds; and ``reports/table1_<learner>.png``: the
objective against each searched key over all trials (defaults and best marked; a trial stopped
early at its lower bound), and the discovery / learning split per seed. Nothing is rerun.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd

from ..studies import Study, Written, command
from ..studies import build as build_study
from .table1_figure import figure, seed_columns
from .trials import TRIALS_FILE
from .space import SearchSpace, SearchSpaceError, available_learners, find_search_space, override_value
from .study import DEFAULTS, study_folder

TABLE_FILE = "table1.md"


def load_trials(path: Path) -> pd.DataFrame:
    trials = pd.read_csv(path, dtype={"role": str})
    # Studies exported before trials could stop early have no such column: all ran to the end.
    stopped = trials["stopped_early"] if "stopped_early" in trials else pd.Series(False, index=trials.index)
    trials["stopped_early"] = stopped.astype(str).str.lower().eq("true")
    return trials


def learner_section(space: SearchSpace, trials: pd.DataFrame | None, budget: int) -> str:
    title = f"## {space.learner}: " + ", ".join(space.base)
    if trials is None or trials.empty:
        return f"{title}\n\nNot tuned yet: no {TRIALS_FILE}.\n"
    complete = trials[~trials["stopped_early"]]
    stopped = len(trials) - len(complete)
    to_the_end = " run to the end" if stopped else ""
    best = complete.loc[complete["objective"].idxmin()]
    defaults = trials[trials["role"] == DEFAULTS]
    default = defaults.iloc[0] if not defaults.empty else None
    seeds = [c.split("seed_")[1] for c in seed_columns(trials, "reward_loss")]
    lines = [
        title, "",
        f"Random search ({space.path.name}, sampler seed {space.sampler_seed}): {len(trials)} "
        f"trial{'' if len(trials) == 1 else 's'} finished, each {len(seeds)} runs without transfer (tuning seeds {', '.join(seeds)}) at "
        f"{budget:,} learning steps (scale {space.scale}). Objective: mean reward loss L_R over the "
        "tuning seeds (lower is better)."
        + ("" if not stopped else
           f" {stopped} of them were stopped early, once the L_R of their finished evaluation points "
           "already exceeded the best finished trial's: their objective is a lower bound, and the "
           "search selects the same best trial as without stopping."), "",
        f"- Best: L_R {best['objective']:.1f} (trial {int(best['trial'])}; per seed "
        f"{_per_seed(best, 'reward_loss')}).",
    ]
    if default is not None:
        lines.append(f"- Provisional defaults, same seeds: L_R {default['objective']:.1f} (trial "
                     f"{int(default['trial'])}; per seed {_per_seed(default, 'reward_loss')}); "
                     f"rank {int((complete['objective'] < default['objective']).sum()) + 1} of "
                     f"{len(complete)}{to_the_end}.")
    lines.append(f"- Median trial{to_the_end}: L_R {complete['objective'].median():.1f}.")
    same = default is not None and int(default["trial"]) == int(best["trial"])
    for label, row in (("best" + (" = defaults" if same else ""), best), ("defaults", None if same else default)):
        if row is not None:
            lines.append(f"- Discovery / learning ({label}), per seed: first rewarded target episode "
                         f"{_per_seed(row, 'first_target_reward_step', steps=True)}; then to the first "
                         f"<R> >= 8 {_per_seed(row, 'learning_span', steps=True)} steps; time to "
                         f"threshold (stable) {_per_seed(row, 'time_to_threshold', steps=True)}.")
    discovery = complete[seed_columns(complete, "first_target_reward_step")]
    if len(complete) > 1 and (discovery.nunique(dropna=False) == 1).all():
        # Measured, not assumed: true for a learner whose weights start at 0 and get no update
        # before the first reward (every TD error is 0), so its exploration is the same walk.
        lines.append("- Discovery does not depend on the searched values: on each tuning seed every "
                     "trial had its first rewarded target episode at the same step "
                     f"({_per_seed(best, 'first_target_reward_step', steps=True)}); the values "
                     "only change the learning after it.")
    tuned = tuned_values(space)
    lines += ["", f"| key | range | provisional default | best trial ({int(best['trial'])}) | "
              f"chosen ({'conf/tuned/' + space.learner_pair() + '.yaml' if tuned else 'none yet'}) | why this range |",
              "|---|---|---:|---:|---:|---|"]
    for p in space.params:
        in_best = best[p.key] if p.key in best else math.nan
        chosen = _value(tuned[p.key]) if p.key in tuned else "-"
        lines.append(f"| `{p.key}` | {_cell(p.describe())} | {_value(space.defaults[p.key])} | "
                     f"{_value(in_best)} | {chosen} | {_cell(p.why)} |")
    lines += ["", f"![objective against each key](table1_{space.learner}.png)", ""]
    return "\n".join(lines)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")  # |MiT| inside a table cell would end the cell


def _per_seed(row: pd.Series, name: str, steps: bool = False) -> str:
    values = [row[c] for c in row.index if c.startswith(f"{name}.seed_")]
    if steps:
        return ", ".join("never" if pd.isna(v) else f"{int(v):,}" for v in values)
    return ", ".join(f"{v:.1f}" for v in values)


def _value(value) -> str:
    if isinstance(value, (bool, np.bool_)) or value is None or isinstance(value, str):
        return override_value(bool(value)) if isinstance(value, (bool, np.bool_)) else str(value)
    if isinstance(value, float) and value.is_integer() and abs(value) >= 100:
        return f"{int(value):,}"
    return f"{value:.4g}"


class Tuned(NamedTuple):
    """One learner's stored study: its search space, its trials (None: not tuned yet), its budget."""

    space: SearchSpace
    trials: pd.DataFrame | None
    budget: int
    folder: Path
    """tuning/<learner>/: trials.csv and the refinement's table."""


def load(root: Path, scale: str | None = None) -> tuple[list[Tuned], Path]:
    """Every search space's committed trials (<root>/tuning/*/trials.csv), and the reports folder."""
    from ..config.compose import compose_config

    root = Path(root)
    tuned, out_dir = [], None
    scales = {}  # composing takes a moment: once per scale
    for learner in available_learners():
        space = find_search_space(learner).with_scale(scale)
        if space.scale not in scales:
            scales[space.scale] = compose_config([f"scale={space.scale}", f"paths.root={root}"])
        scale_cfg = scales[space.scale]
        out_dir = Path(scale_cfg.paths.reports_dir)
        csv = study_folder(root, space) / TRIALS_FILE
        tuned.append(Tuned(space, load_trials(csv) if csv.is_file() else None, int(scale_cfg.scale.budget),
                           csv.parent))
    return tuned, out_dir


def sections(tuned: list[Tuned]) -> list[str]:
    """Per learner, what its trials measured (best, defaults, median, the split) and its refinement."""
    return [text for t in tuned
            for text in (learner_section(t.space, t.trials, t.budget), _refinement_section(t.space, t.folder))]


def report(tuned: list[Tuned], out_dir: Path, texts: list[str]) -> Written:
    """table1.md's text, and each tuned learner's figure (drawn here)."""
    figures = [figure(t.space, t.trials, out_dir / f"table1_{t.space.learner}.png")
               for t in tuned if t.trials is not None and not t.trials.empty]
    text = "\n".join([
        "# Table I: hyperparameters, tuned by random search (issue 9)", "",
        "Built by `make table1` from the committed `tuning/<learner>/trials.csv`; the studies "
        "themselves are `tuning/<learner>/study.db` (resume with `make tune LEARNER=...`). As in the "
        "paper, each learner is tuned for the runs WITHOUT transfer only, on tuning seeds that are "
        "not the table seeds; a stronger baseline can shrink the measured gain from transfer.", "",
        *texts,
    ])
    return Written({out_dir / TABLE_FILE: text}, figures)


def study(root: Path, scale: str | None = None) -> Study:
    """Table I as a registration -> runs -> measures -> report (studies/shape.py): its
    registration is the search spaces, fixed before their trials."""
    return Study("table1", "conf/hparams_search/", lambda: load(root, scale),
                 lambda loaded: (*loaded, sections(loaded[0])), lambda measured: report(*measured))


def build(root: Path, scale: str | None = None) -> list[Path]:
    """Write <reports dir>/table1.md and its figures from <root>/tuning/*/trials.csv."""
    return build_study(study(root, scale))


def tuned_values(space: SearchSpace) -> dict:
    """The values conf/tuned/ holds for the learner of ``space`` ({} before it is tuned)."""
    from omegaconf import OmegaConf

    from ..config.compose import CONF_DIR

    path = CONF_DIR / "tuned" / f"{space.learner_pair()}.yaml"
    if not path.is_file():
        return {}
    data = OmegaConf.to_container(OmegaConf.load(path)) or {}
    return {f"{group}.{key}": value for group, keys in data.items() for key, value in keys.items()}


def _refinement_section(space: SearchSpace, folder: Path) -> str:
    """The manual refinement's table (tuning/refine.py), when one was run for this learner."""
    from .refine import REFINE_FILE, load_refinement, section

    if not (folder / REFINE_FILE).is_file():
        return ""
    try:
        refinement = load_refinement(space.learner, scale=space.scale)
    except SearchSpaceError:
        return ""
    return section(refinement, pd.read_csv(folder / REFINE_FILE))


def _study(argv: list[str]) -> Study:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.tuning.table1", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", type=Path, default=Path("."), help="project root: tuning/, reports/")
    parser.add_argument("--scale", default=None, help="the studies' scale (default: each search space's)")
    args = parser.parse_args(argv)
    return study(args.root, args.scale)


main = command(_study)

if __name__ == "__main__":
    sys.exit(main())
