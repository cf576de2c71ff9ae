"""The short manual refinement after the random search: a few named candidates, run again on
more tuning seeds, so the chosen values are not picked on the noise of three seeds.

``conf/hparams_search/refine/<learner>.yaml`` names the search space (its base overrides and
scale), the refinement's tuning seeds (never table seeds) and the candidates, each a full set
of the searched keys with where it comes from. Every (candidate, seed) run is appended to
``tuning/<learner>/refine.csv`` as it finishes, so an interrupted refinement resumes, and the
file is committed so Table I rebuilds without rerunning.

    python -m mediated_transfer.tuning.refine rbf [--workers 2]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from omegaconf import OmegaConf

from ..progress import duration
from .objective import first_step_at_threshold, run_seed
from .space import SEARCH_SPACE_DIR, SearchSpace, SearchSpaceError, find_search_space

REFINE_FILE = "refine.csv"
COLUMNS = ["candidate", "seed", "reward_loss", "first_target_reward_step", "first_threshold_step",
           "learning_span", "time_to_threshold", "final_reward"]


@dataclass(frozen=True)
class Candidate:
    name: str
    origin: str
    """Where the values come from (a trial of the random search, the defaults, ...)."""
    values: dict[str, Any]


@dataclass(frozen=True)
class Refinement:
    space: SearchSpace
    seeds: tuple[int, ...]
    candidates: tuple[Candidate, ...]

    def runs(self) -> list[tuple[Candidate, int]]:
        """Seed by seed: a refinement stopped midway (a DQN one takes hours) has run every
        candidate on the same seeds, so its partial table compares like with like."""
        return [(c, s) for s in self.seeds for c in self.candidates]


def load_refinement(learner: str, folder: Path = SEARCH_SPACE_DIR, scale: str | None = None) -> Refinement:
    """The refinement of ``learner`` (its search space from ``folder``; ``scale`` replaces the
    search space's, e.g. smoke for a test)."""
    path = folder / "refine" / f"{learner}.yaml"
    if not path.is_file():
        known = sorted(p.stem for p in (folder / "refine").glob("*.yaml"))
        raise SearchSpaceError(f"learner={learner!r} has no refinement file {path}; allowed: {', '.join(known)}")
    data = OmegaConf.to_container(OmegaConf.load(path), resolve=True)
    space = find_search_space(learner, folder).with_scale(scale)
    keys = [p.key for p in space.params]
    seeds = tuple(int(s) for s in data["seeds"])
    table_seeds = set(range(20))
    if table_seeds & set(seeds):
        raise SearchSpaceError(f"{path.name}: seeds must not be table seeds 0-19, got {sorted(table_seeds & set(seeds))}")
    candidates = []
    for name, spec in data["candidates"].items():
        values = {**space.defaults, **(spec.get("values") or {})}
        unknown = sorted(set(values) - set(keys))
        if unknown:
            raise SearchSpaceError(f"{path.name}: candidates.{name}: unknown key(s) {', '.join(unknown)}; "
                                   f"allowed: {', '.join(keys)}")
        candidates.append(Candidate(str(name), str(spec.get("from", "")), values))
    return Refinement(space, seeds, tuple(candidates))


def run_one(space: SearchSpace, candidate: Candidate, seed: int) -> dict[str, Any]:
    """One run of a candidate at a tuning seed, as a row of refine.csv."""
    result, threshold = run_seed(space.run_overrides(candidate.values, seed))
    at_threshold = first_step_at_threshold(result.steps, result.mean_reward, threshold)
    return {
        "candidate": candidate.name, "seed": seed, "reward_loss": result.reward_loss,
        "first_target_reward_step": result.first_target_reward_step, "first_threshold_step": at_threshold,
        "learning_span": result.learning_span(threshold),
        "time_to_threshold": result.time_to_threshold, "final_reward": result.mean_reward[-1],
    }


def refine(refinement: Refinement, folder: Path, workers: int = 1) -> pd.DataFrame:
    """Run every (candidate, seed) missing from folder/refine.csv; returns all rows."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / REFINE_FILE
    done = pd.read_csv(path) if path.is_file() else pd.DataFrame(columns=COLUMNS)
    have = {(str(c), int(s)) for c, s in zip(done["candidate"], done["seed"])}
    todo = [(c, s) for c, s in refinement.runs() if (c.name, s) not in have]
    print(f"[refine {refinement.space.learner}] {len(have)} runs done, {len(todo)} to run, {workers} worker(s)")
    total, start = len(have) + len(todo), time.monotonic()
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(run_one, refinement.space, c, s): (c.name, s) for c, s in todo}
        for finished, future in enumerate(as_completed(futures), 1):
            row = future.result()
            # One writer (this process), one appended line per finished run: nothing is lost.
            pd.DataFrame([row], columns=COLUMNS).to_csv(path, mode="a", header=not path.is_file(), index=False)
            left = (time.monotonic() - start) / finished * (len(todo) - finished)
            print(f"[refine {refinement.space.learner} {len(have) + finished}/{total}, ~{duration(left)} left] "
                  f"{row['candidate']} seed={row['seed']}: L_R {row['reward_loss']:.1f}", flush=True)
    return pd.read_csv(path)


def summary(refinement: Refinement, rows: pd.DataFrame) -> pd.DataFrame:
    """Per candidate: runs, mean L_R +/- SEM, mean learning span, runs reaching <R> >= 8."""
    out = []
    for c in refinement.candidates:
        mine = rows[(rows["candidate"] == c.name) & rows["seed"].isin(refinement.seeds)]
        losses = mine["reward_loss"].to_numpy(float)
        spans = mine["learning_span"].dropna().to_numpy(float)
        out.append({
            "candidate": c.name, "from": c.origin, "runs": len(mine),
            "reward_loss_mean": float(losses.mean()) if len(losses) else math.nan,
            "reward_loss_sem": float(losses.std(ddof=1) / np.sqrt(len(losses))) if len(losses) > 1 else math.nan,
            "learning_span_mean": float(spans.mean()) if len(spans) else math.nan,
            "reached": int(mine["first_threshold_step"].notna().sum()),
        })
    return pd.DataFrame(out).sort_values("reward_loss_mean", kind="stable").reset_index(drop=True)


def section(refinement: Refinement, rows: pd.DataFrame) -> str:
    """Table I's refinement part: what ran, the candidates' values and their result."""
    table = summary(refinement, rows)
    keys = [p.key for p in refinement.space.params]
    lines = [f"Refinement (conf/hparams_search/refine/{refinement.space.learner}.yaml): {len(refinement.candidates)} candidates x "
             f"{len(refinement.seeds)} tuning seeds ({refinement.seeds[0]}-{refinement.seeds[-1]}); "
             "best first. Learning span: steps from the first rewarded target episode to the first "
             "<R> >= 8 (mean over the runs that reach it).", "",
             "| candidate | from | runs | L_R | learning span | reached <R> >= 8 | " + " | ".join(f"`{k}`" for k in keys) + " |",
             "|---|---|---:|---:|---:|---:|" + "---:|" * len(keys)]
    done, planned = int(table["runs"].sum()), len(refinement.runs())
    if done < planned:
        lines[0] += (f" **Not finished: {done} of {planned} runs so far** (seed by seed, so the "
                     "candidates share their seeds).")
    by_name = {c.name: c for c in refinement.candidates}
    for _, r in table.iterrows():
        values = [_fmt(by_name[r["candidate"]].values[k]) for k in keys]
        span = "-" if math.isnan(r["learning_span_mean"]) else f"{r['learning_span_mean']:,.0f}"
        loss = ("-" if math.isnan(r["reward_loss_mean"]) else f"{r['reward_loss_mean']:.1f}"
                + ("" if math.isnan(r["reward_loss_sem"]) else f" ± {r['reward_loss_sem']:.1f}"))
        lines.append(f"| {r['candidate']} | {r['from']} | {r['runs']} | {loss} | {span} | "
                     f"{r['reached']}/{r['runs']} | " + " | ".join(values) + " |")
    return "\n".join(lines) + "\n"


def _fmt(value: Any) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.tuning.refine", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("learner")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--root", type=Path, default=Path("."), help="project root: tuning/")
    parser.add_argument("--scale", default=None, help="conf/scale option (default: the search space's)")
    args = parser.parse_args(argv)
    try:
        refinement = load_refinement(args.learner, scale=args.scale)
    except SearchSpaceError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    folder = args.root / "tuning" / refinement.space.learner
    if refinement.space.scale != "paper":
        folder = folder / refinement.space.scale  # a reduced scale never mixes with the paper's
    rows = refine(refinement, folder, args.workers)
    print(section(refinement, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
