"""``python -m mediated_transfer.reporting.ablation``: reports/dqn_failure_ablation.md, the
pre-registered study of why the tuned DQN without transfer sometimes never learns
(conf/experiment/dqn_failure_ablation.yaml: hypotheses, arms, seeds and decision rule were fixed
there before any run). This module applies that rule to the committed runs and nothing else:

- the primary outcome per arm is the number of runs that never learn (no evaluation point at
  <R> >= 8);
- an arm *removes the failure* when it has fewer such runs than the Table I arm by a one-sided
  Fisher exact test at p < 0.05;
- H1 (the replay buffer forgets the early rewards) is supported when the buffer arm removes the
  failure and the epsilon arm does not; H2 (exploration ends too early) the other way round;
- when the Table I arm fails so rarely that even an arm with no failure could not reach
  p < 0.05 (at 20 runs an arm: fewer than 5 failures), the study cannot decide, and says so.

Secondary measures: mean L_R and its ratio to the Table I arm with a 95 % bootstrap interval,
and, for the runs that never learn, the first rewarded target episode and the final TD loss.
Beside them, marked exploratory and outside the rule: every run's curve per arm (a figure) and
L_R per seed and arm.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf
from scipy import stats

from ..config.compose import CONF_DIR
from ..results import RunResult
from .collect import collect_sweep, runs_per_variant
from .figures import RunPanel, plot_run_panels
from .intervals import format_interval, iqm, ratio_of_means, sem
from .reproduction.runs import MAX_REWARD, THRESHOLD, never_learns
from .reproduction.tables import NEVER_LEARN_COLUMNS, never_learn_row
from ..studies import Study, Written, command

EXPERIMENT = "dqn_failure_ablation"
CELL = "none_0"
RUNS_PER_ARM = 20  # the design's seeds 2000-2019
ALPHA = 0.05
FACTORS = ("buffer_size", "epsilon_decay_steps")
PERMUTATIONS = 10_000  # of the exploratory seed-clustering test


def table_i_values(conf_dir: Path = CONF_DIR) -> tuple[int, int]:
    """Table I's buffer size and epsilon decay, read from where Table I keeps them."""
    tuned = OmegaConf.load(conf_dir / "tuned" / "dqn_network.yaml").algorithm
    return tuple(int(tuned[f]) for f in FACTORS)


@dataclass
class Arm:
    """One arm of the 2 x 2 design: its factor values and its finished runs."""

    buffer_size: int
    epsilon_decay_steps: int
    runs: list[RunResult]

    def changed(self, table_i: tuple[int, int]) -> tuple[bool, bool]:
        """Which factors differ from Table I's: (buffer, epsilon decay)."""
        return self.buffer_size != table_i[0], self.epsilon_decay_steps != table_i[1]

    def name(self, table_i: tuple[int, int]) -> str:
        changed = [f"{label} {value:,}" for label, value, differs in
                   zip(("buffer", "ε decay"), (self.buffer_size, self.epsilon_decay_steps), self.changed(table_i))
                   if differs]
        return "Table I" if not changed else " + ".join(changed)

    @property
    def never_learn(self) -> list[RunResult]:
        return [r for r in self.runs if never_learns(r)]

    @property
    def losses(self) -> np.ndarray:
        return np.array([r.reward_loss for r in self.runs])


def fewer_failures_p(failures: int, runs: int, reference_failures: int, reference_runs: int) -> float:
    """One-sided Fisher exact p that an arm with ``failures`` of ``runs`` fails less often than
    the reference arm with ``reference_failures`` of ``reference_runs``."""
    table = [[failures, runs - failures], [reference_failures, reference_runs - reference_failures]]
    return float(stats.fisher_exact(table, alternative="less").pvalue)


def decidable(reference_failures: int, reference_runs: int, runs: int) -> bool:
    """Whether any result of an arm of ``runs`` runs (even none failing) could reach p < ALPHA
    against the reference arm."""
    return fewer_failures_p(0, runs, reference_failures, reference_runs) < ALPHA


def decide(buffer_arm: tuple[int, int], epsilon_arm: tuple[int, int], reference: tuple[int, int]) -> str:
    """The pre-registered rule on (failures, runs) of the two single-factor arms and of the
    Table I arm: which hypothesis the runs support, or why they support none."""
    ref_fail, ref_runs = reference
    if not decidable(ref_fail, ref_runs, min(buffer_arm[1], epsilon_arm[1])):
        return (f"cannot decide: with {ref_fail} of {ref_runs} Table I runs that never learn, even an arm "
                f"without failures could not reach p < {ALPHA}")
    removes = {h: fewer_failures_p(*arm, *reference) < ALPHA
               for h, arm in (("H1", buffer_arm), ("H2", epsilon_arm))}
    if removes["H1"] and removes["H2"]:
        return "both single-factor arms remove the failure: neither hypothesis alone is supported"
    if removes["H1"]:
        return "H1 supported: the larger buffer removes the failure, the longer ε decay does not"
    if removes["H2"]:
        return "H2 supported: the longer ε decay removes the failure, the larger buffer does not"
    return "neither supported: no single-factor arm has significantly fewer runs that never learn"


def load(root: Path, scale: str = "paper") -> tuple[dict[tuple[int, int], Arm], list[RunResult]]:
    """The study's runs that ran their budget by (buffer size, epsilon decay), and the runs
    stopped as diverged (named in the report, in no arm's statistics). Every variant folder of
    the sweep is one arm, keyed by the values its runs record."""
    sweep = root / "multirun" / EXPERIMENT / scale
    arms: dict[tuple[int, int], Arm] = {}
    diverged: list[RunResult] = []
    for variant in (runs_per_variant(sweep) if sweep.is_dir() else {}):
        cell = collect_sweep(sweep, algorithm="dqn", variant=variant).get(CELL)
        if cell is None:
            continue
        diverged += cell.failed
        for run in cell.results:
            key = tuple(int(run.config["algorithm"][f]) for f in FACTORS)
            arms.setdefault(key, Arm(*key, [])).runs.append(run)
    for arm in arms.values():
        arm.runs.sort(key=lambda r: r.seed)
    return arms, diverged


def ordered(arms: dict[tuple[int, int], Arm], table_i: tuple[int, int]) -> list[Arm]:
    """Table I's arm, then the buffer arm (H1), the epsilon arm (H2), and both changed."""
    return sorted(arms.values(), key=lambda a: (sum(a.changed(table_i)), a.changed(table_i)[1]))


def plot(arms: dict[tuple[int, int], Arm], table_i: tuple[int, int], path: Path) -> Path:
    """Every run's curve, a panel per arm: the failure is bimodal, so single curves, not means."""
    panels = [RunPanel(f"{arm.name(table_i)}\nbuffer {arm.buffer_size:,}, ε decay {arm.epsilon_decay_steps:,}",
                       [r.steps for r in arm.runs], [r.mean_reward for r in arm.runs])
              for arm in ordered(arms, table_i)]
    return plot_run_panels(panels, THRESHOLD, MAX_REWARD,
                           "DQN without transfer: every run's curve per arm (red: never reaches the threshold)",
                           path)


def render(arms: dict[tuple[int, int], Arm], table_i: tuple[int, int], diverged: list[RunResult] = (),
           figure: str | None = None) -> str:
    lines = ["# Pre-registered: why the tuned DQN without transfer sometimes never learns", "",
             "Generated by `python -m mediated_transfer.reporting.ablation` (`make dqn-ablation`) from the "
             f"committed runs of `conf/experiment/{EXPERIMENT}.yaml`, which fixed the hypotheses, arms, "
             "seeds and decision rule before any run; do not edit by hand.", "",
             "Without transfer, some runs of the tuned DQN find the target task's reward and still never "
             "learn. H1: the replay buffer forgets the few early rewarded transitions before the network "
             "has learned from them. H2: exploration ends too early (ε reaches 0.1 within Table I's decay). "
             "A hypothesis is supported when its arm has fewer runs that never learn than the Table I arm "
             f"(one-sided Fisher exact test, p < {ALPHA}) and the other single-factor arm has not.", ""]
    reference = arms.get(table_i)
    if reference is None or not reference.runs:
        return "\n".join(lines + ["No runs of the Table I arm yet: "
                                  f"`python -m mediated_transfer experiment={EXPERIMENT}`.", ""])
    total = sum(len(a.runs) for a in arms.values())
    if total < 4 * RUNS_PER_ARM:
        lines += [f"**Incomplete:** {total} of {4 * RUNS_PER_ARM} runs; the decision below is provisional.", ""]
    if diverged:
        lines += ["Stopped as diverged, in no arm: " + ", ".join(
            f"seed {r.seed} ({r.failure})" for r in diverged) + ".", ""]
    ref_never = len(reference.never_learn)
    lines += ["| arm | buffer | ε decay (steps) | runs | never learn | p (fewer than Table I) | "
              "L_R mean ± SEM | IQM | L_R ratio to Table I [95 % CI] |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    order = ordered(arms, table_i)
    for arm in order:
        losses = arm.losses
        is_ref = arm is reference
        p = "" if is_ref else f"{fewer_failures_p(len(arm.never_learn), len(arm.runs), ref_never, len(reference.runs)):.3f}"
        ratio = "" if is_ref else format_interval(ratio_of_means(losses, reference.losses))
        lines.append(f"| {arm.name(table_i)} | {arm.buffer_size:,} | {arm.epsilon_decay_steps:,} | {len(arm.runs)} | "
                     f"{len(arm.never_learn)} | {p} | {losses.mean():.1f} ± {sem(losses):.1f} | {iqm(losses):.1f} | {ratio} |")
    single = {("buffer" if arm.changed(table_i)[0] else "epsilon"): (len(arm.never_learn), len(arm.runs))
              for arm in arms.values() if sum(arm.changed(table_i)) == 1}
    lines += [""]
    if set(single) == {"buffer", "epsilon"}:
        lines += [f"**Decision:** {decide(single['buffer'], single['epsilon'], (ref_never, len(reference.runs)))}.", ""]
    else:
        lines += ["**Decision:** not yet: a single-factor arm has no runs.", ""]
    if figure:
        lines += [f"![Every run's curve, a panel per arm]({figure})", ""]
    header, rule = NEVER_LEARN_COLUMNS
    lines += ["## The runs that never learn", "", "| arm " + header, "|---" + rule]
    lines += [f"| {arm.name(table_i)} {never_learn_row(r)}" for arm in order for r in arm.never_learn]
    return "\n".join(lines + [""] + by_seed(order, table_i))


def seed_clustering_p(failed: np.ndarray, permutations: int = PERMUTATIONS, seed: int = 0) -> float:
    """How often failures gather on seeds by chance: ``failed`` is arms x seeds (True: never
    learns). The statistic is the variance over seeds of the number of arms that fail there; the
    null shuffles each arm's failures across the seeds on its own (each arm keeps its count).
    Returns the share of permutations at least as clustered as observed (seeded, so rebuilt
    reports agree)."""
    failed = np.asarray(failed, dtype=int)
    observed = failed.sum(axis=0).var()
    rng = np.random.default_rng(seed)
    shuffled = rng.permuted(np.broadcast_to(failed, (permutations, *failed.shape)), axis=2)
    return float((shuffled.sum(axis=1).var(axis=1) >= observed - 1e-12).mean())


def by_seed(order: list[Arm], table_i: tuple[int, int]) -> list[str]:
    """L_R per seed and arm, the runs that never learn marked. Exploratory, outside the
    registered rule: the arms share their seeds, so failures that gather on a seed across arms
    more than chance gives (``seed_clustering_p``) would point at what a seed fixes (the
    network's initialisation, the first episodes) rather than at the buffer or the ε schedule."""
    runs = {(i, r.seed): r for i, arm in enumerate(order) for r in arm.runs}
    seeds = sorted({seed for _, seed in runs})
    lines = ["## By seed (exploratory, not part of the registered rule)", "",
             "The arms share their seeds, and a seed fixes the network's initialisation and the "
             "exploration's random draws; up to the step at which the smaller buffer is full "
             f"({table_i[0]:,}), the two arms that differ only in the buffer are the same run. "
             "L_R per run; **bold**: never learns.", "",
             "| seed | " + " | ".join(arm.name(table_i) for arm in order) + " | never learn |",
             "|---:|" + "---:|" * len(order) + "---:|"]
    for seed in seeds:
        cells = [runs.get((i, seed)) for i in range(len(order))]
        shown = ["" if r is None else (f"**{r.reward_loss:.1f}**" if never_learns(r) else f"{r.reward_loss:.1f}")
                 for r in cells]
        failed = sum(r is not None and never_learns(r) for r in cells)
        lines.append(f"| {seed} | " + " | ".join(shown) + f" | {failed} of {sum(r is not None for r in cells)} |")
    complete = [seed for seed in seeds if all((i, seed) in runs for i in range(len(order)))]
    if len(order) > 1 and complete:
        never = np.array([[never_learns(runs[i, seed]) for seed in complete] for i in range(len(order))])
        lines += ["", f"Do failures gather on seeds more than chance gives? Over the {len(complete)} seeds "
                  "that every arm has run, shuffling each arm's runs that never learn across those seeds "
                  f"({PERMUTATIONS:,} permutations, each arm keeping its count) spreads the failures per seed at "
                  f"least as unevenly as observed in p = {seed_clustering_p(never):.3f} of them."]
    return lines + [""]


def study(argv: list[str]) -> Study:
    """The ablation as a registration -> runs -> measures -> report (studies/shape.py)."""
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.reporting.ablation",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=".", help="the checkout whose multirun/ holds the runs")
    parser.add_argument("--scale", default="paper", help="the study's scale (its design is the paper's)")
    parser.add_argument("--out", default=None, help=f"where to write (default: <root>/reports/{EXPERIMENT}.md)")
    args = parser.parse_args(argv)
    root = Path(args.root)
    out = Path(args.out) if args.out else root / "reports" / f"{EXPERIMENT}.md"

    def report(measured: tuple[dict[tuple[int, int], Arm], list[RunResult], tuple[int, int]]) -> Written:
        arms, diverged, table_i = measured
        out.parent.mkdir(parents=True, exist_ok=True)
        figure = plot(arms, table_i, out.with_suffix(".png")) if arms.get(table_i) else None
        return Written({out: render(arms, table_i, diverged, figure and figure.name)}, [figure] if figure else [])

    # The measures are the rule's counts and tests, taken as render words them: Table I's values
    # join the runs here, as the registration fixed them.
    return Study(EXPERIMENT, f"conf/experiment/{EXPERIMENT}.yaml", lambda: load(root, args.scale),
                 lambda runs: (*runs, table_i_values()), report,
                 lambda runs: [r for arm in runs[0].values() for r in arm.runs] + runs[1])


main = command(study)

if __name__ == "__main__":
    sys.exit(main())
