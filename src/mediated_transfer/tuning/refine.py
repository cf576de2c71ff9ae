"""The short manual refinement after the random search: a few named candidates, run again on
more tuning seeds, so the chosen values are not picked on the noise of three seeds.

``conf/hparams_search/refine/<learner>.yaml`` names the search space (its base overrides and
scale), the refinement's tuning seeds (never table seeds) and the candidates, each a full set
of the searched keys with where it comes from. Every (candidate, seed) run is appended to
``tuning/<learner>/refine.csv`` as it finishes, so an interrupted refinement resumes, and the
file is committed so Table I rebuilds without rerunning.

A refinement file may race its candidates (``racing``: the racing of Birattari et al. 2002,
with a paired t-test against the leader rather than F-race's Friedman test): after each seed
every remaining candidate has run, from ``min_seeds`` seeds on, a candidate whose mean L_R is
above the leader's by more than the leader's SEM, and worse than the leader's on those seeds by
a one-sided paired t-test at ``p_value``, gets no more runs. The test is repeated at every seed
against a leader picked from the same data, so the chance of dropping a candidate as good as
the leader is above ``p_value``; the SEM margin guards the candidates the choice could still
pick. The decision is a function of the rows in seed order, so a resumed refinement drops
exactly the same candidates, and a dropped candidate's table counts its runs up to the drop.

    python -m mediated_transfer.tuning.refine rbf [--workers 2]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import deque
from collections.abc import Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from omegaconf import OmegaConf
from scipy import stats

from ..sweep.progress import duration
from .objective import first_step_at_threshold, run_seed
from .space import SEARCH_SPACE_DIR, SearchSpace, SearchSpaceError, find_search_space

REFINE_FILE = "refine.csv"
CHOICE_RULES = {
    "lowest_mean": "the lowest mean L_R",
    "cheapest_within_one_sem": ("the one-standard-error rule: the cheapest candidate, in gradient-update FLOPs "
                                "per learning step, whose mean L_R is within one SEM of the lowest mean"),
}
"""How a refinement chooses its candidate (the refinement file's ``choice``; lowest_mean when
it names none)."""
COLUMNS = ["candidate", "seed", "reward_loss", "first_target_reward_step", "first_threshold_step",
           "learning_span", "time_to_threshold", "final_reward"]


@dataclass(frozen=True)
class Candidate:
    name: str
    origin: str
    """Where the values come from (a trial of the random search, the defaults, ...)."""
    values: dict[str, Any]


@dataclass(frozen=True)
class Racing:
    """When a candidate is clearly out of the race (module docstring)."""

    min_seeds: int
    """Seeds every remaining candidate has run before any is dropped."""
    p_value: float
    """Level of the one-sided paired t-test against the leader."""


@dataclass(frozen=True)
class Drop:
    """A candidate racing dropped: after which seed, and why (markdown)."""

    seed: int
    why: str


@dataclass(frozen=True)
class Refinement:
    space: SearchSpace
    seeds: tuple[int, ...]
    candidates: tuple[Candidate, ...]
    choice: str = "lowest_mean"
    racing: Racing | None = None

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
    choice = str(data.get("choice", "lowest_mean"))
    if choice not in CHOICE_RULES:
        raise SearchSpaceError(f"{path.name}: choice must be one of {', '.join(CHOICE_RULES)}, got {choice!r}")
    if choice == "cheapest_within_one_sem" and not _is_dqn(space):
        raise SearchSpaceError(f"{path.name}: choice {choice!r} needs a run cost, known for the dqn learner only")
    racing = data.get("racing")
    if racing is not None:
        if not isinstance(racing, dict) or set(racing) != {"min_seeds", "p_value"}:
            raise SearchSpaceError(f"{path.name}: racing needs exactly min_seeds and p_value, got {racing!r}")
        racing = Racing(int(racing["min_seeds"]), float(racing["p_value"]))
        if not 2 <= racing.min_seeds <= len(seeds) or not 0 < racing.p_value < 1:
            raise SearchSpaceError(f"{path.name}: racing.min_seeds must be in 2..{len(seeds)} (the seeds) and "
                                   f"racing.p_value in (0, 1), got {racing.min_seeds} and {racing.p_value}")
    return Refinement(space, seeds, tuple(candidates), choice, racing)


def _is_dqn(space: SearchSpace) -> bool:
    return space.learner_pair().startswith("dqn_")


def dropped(refinement: Refinement, rows: pd.DataFrame) -> dict[str, Drop]:
    """The candidates racing has dropped given ``rows``; {} without racing. Seeds are taken in
    order, each once every remaining candidate has run it."""
    racing = refinement.racing
    if racing is None:
        return {}
    loss = {(str(c), int(s)): float(v) for c, s, v in zip(rows["candidate"], rows["seed"], rows["reward_loss"])}
    alive, out = [c.name for c in refinement.candidates], {}
    for j, seed in enumerate(refinement.seeds, 1):
        if any((c, seed) not in loss for c in alive):
            break
        if j < racing.min_seeds:
            continue
        seeds = refinement.seeds[:j]
        per_seed = {c: np.array([loss[c, s] for s in seeds]) for c in alive}
        leader = min(alive, key=lambda c: per_seed[c].mean())
        lead = per_seed[leader]
        for c in alive:
            diff = per_seed[c] - lead
            if c == leader or not diff.mean() > lead.std(ddof=1) / math.sqrt(j):
                continue
            # A constant positive difference has no variance: the t-test has no p, the case is clear.
            p = 0.0 if np.ptp(diff) == 0 else float(stats.ttest_1samp(diff, 0.0, alternative="greater").pvalue)
            if p < racing.p_value:
                out[c] = Drop(seed, f"dropped after seed {seed} ({j} seeds): L_R {per_seed[c].mean():.1f} "
                                    f"against `{leader}`'s {lead.mean():.1f}, paired t-test p = {p:.2g}")
        alive = [c for c in alive if c not in out]
    return out


def _work(refinement: Refinement, candidate: Candidate) -> float:
    """A run's share of the refinement's compute, for the time left: its update cost for the
    DQN, whose candidates' runs differ 16-fold; 1 for any other learner."""
    return update_cost(candidate.values) if _is_dqn(refinement.space) else 1.0


def _compute_left(refinement: Refinement, per_work: float, running, waiting) -> float:
    """Seconds of compute left at ``per_work`` seconds per unit of work: the runs waiting, and
    what remains of those under way ((candidate, start time) pairs)."""
    now = time.monotonic()
    return (sum(max(0.0, per_work * _work(refinement, c) - (now - started)) for c, started in running)
            + per_work * sum(_work(refinement, c) for c in waiting))


def update_cost(values: dict[str, Any]) -> float:
    """Nominal FLOPs of gradient updates per learning step of a DQN candidate: the part of a
    run's cost the candidates change (batch size, train frequency; the environment's share is
    the same for all). A train-frequency-1, batch-128 candidate does 16 times the defaults' update work."""
    from ..learners.dqn import DQNConfig, update_flops

    config = DQNConfig(**{k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("algorithm.")})
    return update_flops(config) / config.train_frequency


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
    """Run every (candidate, seed) missing from folder/refine.csv, except a dropped candidate's
    (racing); returns all rows."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / REFINE_FILE
    rows = pd.read_csv(path) if path.is_file() else pd.DataFrame(columns=COLUMNS)
    have = {(str(c), int(s)) for c, s in zip(rows["candidate"], rows["seed"])}
    out = dropped(refinement, rows)
    queue = deque((c, s) for c, s in refinement.runs() if (c.name, s) not in have and c.name not in out)
    print(f"[refine {refinement.space.learner}] {len(have)} runs done, {len(queue)} to run, {workers} worker(s)"
          + (f"; dropped by racing: {', '.join(out)}" if out else ""))
    # The time left, from the time per unit of work so far: a DQN candidate's run costs 1x to 16x.
    finished, spent, done_work, running, errors = 0, 0.0, 0.0, {}, []
    with ProcessPoolExecutor(max_workers=workers) as pool:
        # Submitted as workers free up (so a run starts when it is submitted), and a candidate
        # dropped meanwhile starts no further run.
        def fill() -> None:
            while queue and len(running) < workers and not errors:
                c, s = queue.popleft()
                if c.name not in out:
                    running[pool.submit(run_one, refinement.space, c, s)] = (c, time.monotonic())
        fill()
        while running:
            for future in wait(running, return_when=FIRST_COMPLETED).done:
                candidate, started = running.pop(future)
                if future.exception() is not None:
                    errors.append(future.exception())  # raised once the runs still going are saved
                    continue
                row = future.result()
                # One writer (this process), one appended line per finished run: nothing is lost.
                pd.DataFrame([row], columns=COLUMNS).to_csv(path, mode="a", header=not path.is_file(), index=False)
                rows = pd.concat([rows, pd.DataFrame([row], columns=COLUMNS)], ignore_index=True)
                finished += 1
                spent, done_work = spent + time.monotonic() - started, done_work + _work(refinement, candidate)
                newly = {c: drop for c, drop in dropped(refinement, rows).items() if c not in out}
                out.update(newly)
                waiting = [c for c, _ in queue if c.name not in out]
                total = len(have) + finished + len(running) + len(waiting)
                left = _compute_left(refinement, spent / done_work, running.values(), waiting) / workers
                print(f"[refine {refinement.space.learner} {len(have) + finished}/{total}, ~{duration(left)} left] "
                      f"{row['candidate']} seed={row['seed']}: L_R {row['reward_loss']:.1f}", flush=True)
                for c, drop in newly.items():
                    print(f"[refine {refinement.space.learner}] {c} {drop.why}", flush=True)
            fill()
    if errors:
        raise errors[0]
    return pd.read_csv(path)


def summary(refinement: Refinement, rows: pd.DataFrame) -> pd.DataFrame:
    """Per candidate: runs, mean L_R +/- SEM, mean learning span, runs reaching <R> >= 8, and
    whether racing dropped it (then over its seeds up to the drop: a run that was under way
    at the drop counts or not by chance)."""
    out, drops = [], dropped(refinement, rows)
    for c in refinement.candidates:
        drop = drops.get(c.name)
        seeds = refinement.seeds if drop is None else refinement.seeds[:refinement.seeds.index(drop.seed) + 1]
        mine = rows[(rows["candidate"] == c.name) & rows["seed"].isin(seeds)]
        losses = mine["reward_loss"].to_numpy(float)
        spans = mine["learning_span"].dropna().to_numpy(float)
        out.append({
            "candidate": c.name, "from": c.origin, "runs": len(mine),
            "reward_loss_mean": float(losses.mean()) if len(losses) else math.nan,
            "reward_loss_sem": float(losses.std(ddof=1) / np.sqrt(len(losses))) if len(losses) > 1 else math.nan,
            "learning_span_mean": float(spans.mean()) if len(spans) else math.nan,
            "reached": int(mine["first_threshold_step"].notna().sum()),
            "update_cost": update_cost(c.values) if _is_dqn(refinement.space) else math.nan,
            "dropped": drop is not None,
        })
    return pd.DataFrame(out).sort_values("reward_loss_mean", kind="stable").reset_index(drop=True)


def choose(refinement: Refinement, rows: pd.DataFrame) -> tuple[str, str] | None:
    """The candidate the refinement's rule picks from the runs so far, and why in a sentence
    (markdown); None before any run."""
    table = summary(refinement, rows).dropna(subset=["reward_loss_mean"])
    table = table[~table["dropped"]]
    if table.empty:
        return None
    best = table.iloc[0]
    chosen = best
    if refinement.choice == "cheapest_within_one_sem":
        sem = 0.0 if math.isnan(best["reward_loss_sem"]) else best["reward_loss_sem"]
        band = table[table["reward_loss_mean"] <= best["reward_loss_mean"] + sem]
        chosen = band.sort_values(["update_cost", "reward_loss_mean"], kind="stable").iloc[0]
    why = f"`{chosen['candidate']}`, L_R {_loss(chosen)}"
    if chosen["candidate"] != best["candidate"]:
        why += (f": within one SEM of the lowest mean (`{best['candidate']}`, {_loss(best)}) at "
                f"{chosen['update_cost'] / best['update_cost']:.2g} of its update cost")
    return str(chosen["candidate"]), why


def _loss(row: pd.Series) -> str:
    if math.isnan(row["reward_loss_mean"]):
        return "-"
    sem = "" if math.isnan(row["reward_loss_sem"]) else f" ± {row['reward_loss_sem']:.1f}"
    return f"{row['reward_loss_mean']:.1f}{sem}"


def section(refinement: Refinement, rows: pd.DataFrame) -> str:
    """Table I's refinement part: what ran, the candidates' values, their result and the choice."""
    table = summary(refinement, rows)
    keys = [p.key for p in refinement.space.params]
    costs = _is_dqn(refinement.space)
    lines = [f"Refinement (conf/hparams_search/refine/{refinement.space.learner}.yaml): {len(refinement.candidates)} candidates x "
             f"{len(refinement.seeds)} tuning seeds ({refinement.seeds[0]}-{refinement.seeds[-1]}); "
             "best first. Learning span: steps from the first rewarded target episode to the first "
             "<R> >= 8 (mean over the runs that reach it)."
             + (" Update cost: gradient-update FLOPs per learning step, as a multiple of the provisional "
                "defaults'." if costs else ""), "",
             "| candidate | from | runs | L_R | learning span | reached <R> >= 8 | " + ("update cost | " if costs else "")
             + " | ".join(f"`{k}`" for k in keys) + " |",
             "|---|---|---:|---:|---:|---:|" + ("---:|" if costs else "") + "---:|" * len(keys)]
    out = dropped(refinement, rows)
    done = int(table["runs"].sum())
    # A dropped candidate's runs so far are all it will have.
    planned = sum(r["runs"] if r["dropped"] else len(refinement.seeds) for _, r in table.iterrows())
    if done < planned:
        lines[0] += (f" **Not finished: {done} of {planned} runs so far** (seed by seed, so the "
                     "candidates share their seeds).")
    by_name = {c.name: c for c in refinement.candidates}
    unit = update_cost(refinement.space.defaults) if costs else math.nan
    for _, r in table.iterrows():
        values = [_fmt(by_name[r["candidate"]].values[k]) for k in keys]
        span = "-" if math.isnan(r["learning_span_mean"]) else f"{r['learning_span_mean']:,.0f}"
        cost = f"{r['update_cost'] / unit:.2g}x | " if costs else ""
        runs = f"{r['runs']} (dropped)" if r["dropped"] else str(r["runs"])
        lines.append(f"| {r['candidate']} | {r['from']} | {runs} | {_loss(r)} | {span} | "
                     f"{r['reached']}/{r['runs']} | {cost}" + " | ".join(values) + " |")
    if out:
        lines += ["", f"Racing (from {refinement.racing.min_seeds} seeds on; one-sided paired t-test against the "
                      f"leader at p < {refinement.racing.p_value:g}) dropped:", ""]
        lines += [f"- `{c}`: {drop.why}" for c, drop in out.items()]
    chosen = choose(refinement, rows)
    if chosen is not None:
        lines += ["", f"{'Chosen' if done == planned else '**Leading so far**'} by the refinement's rule "
                      f"({CHOICE_RULES[refinement.choice]}): {chosen[1]}."]
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
