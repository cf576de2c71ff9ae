"""The paper's open question in REPRODUCTION.md and the README's headline: Table V's registered
answer (reporting/transfer_answer.py) from its paper-scale runs, or where Table V stands. The
words are transfer_answer's, so the two reports cannot word the answer differently."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from .. import transfer_answer as registered_answer  # a module: it imports this package's runs.py
from ..collect import collect_sweep
from ..intervals import format_interval
from .wording import steps_k

SCALE = "paper"


@dataclass(frozen=True)
class OpenQuestion:
    registered: registered_answer.Registered
    measures: registered_answer.Measures | None
    """None while Table V has no paper-scale runs without transfer."""

    @property
    def expected(self) -> int:
        return len(self.registered.cells) * self.registered.runs_per_row

    @property
    def finished(self) -> int:
        return self.measures.finished if self.measures else 0

    @property
    def complete(self) -> bool:
        return self.measures is not None and self.finished >= self.expected

    def status(self) -> str:
        """The answer in the rule's words once every registered run is in; until then, where the
        sweep stands: the rule's intervals are registered for the full rows, and a row of a few
        runs has an interval too narrow to trust (of one run, none at all)."""
        command = f"`make reproduce-tables EXPERIMENTS={self.registered.experiment}`"
        if self.measures is None or self.measures.reference is None or not self.measures.reference.results:
            return f"not yet run ({self.finished} of {self.expected} runs; {command})"
        if not self.complete:
            return (f"running, {self.finished} of {self.expected} runs; the registered answer comes when all "
                    f"are in ({command} resumes the sweep)")
        return registered_answer.answer(self.measures.best, self.measures.rows, self.measures.learner)

    def split(self) -> str:
        """The discovery / learning split of none_0 and each strategy's best row, in one sentence
        (once the answer is given)."""
        if not self.complete:
            return ""
        splits = {s.cell: s for s in self.measures.splits}
        wanted = [registered_answer.REFERENCE, *(row.cell for row in self.measures.best.values())]
        parts = [f"{s.cell}: {_source_phase(s.source_phase)}{_median_run(s.discovery[0], 'discovers the target reward at')}, "
                 f"then {_median_run(s.learning[0], 'learns the pull in', ' more')} ({s.learned} of {s.runs} runs learn it)"
                 for s in (splits[c] for c in wanted if c in splits)]
        return ("Medians over runs: " + "; ".join(parts) + ".") if parts else ""

    def typical_run(self) -> str:
        """Outside the rule (added after the runs; it decides nothing): the ratio of median L_R of each
        strategy's best row, whether the typical run gains or only the slowest runs."""
        if not self.complete or not self.measures.rows:
            return ""
        parts = [f"{row.cell} {format_interval(row.median_ratio)}" for row in self.measures.best.values()]
        return ("Outside the rule (added after the runs; it decides nothing), the ratio of median L_R: "
                + "; ".join(parts) + ".")


def _source_phase(steps: float | None) -> str:
    """'the source phase ends at 33k (median), ' for a row with one: discovery's steps include it."""
    return "" if steps is None else f"the source phase ends at {registered_answer.phase_steps(steps)} (median), "


def _median_run(steps: float, verb: str, tail: str = "") -> str:
    """'the median run <verb> 40k<tail>', or 'the median run never does' when more than half never do."""
    return f"the median run {verb} {steps_k(steps)}{tail}" if math.isfinite(steps) else "the median run never does"


def read(root: Path) -> OpenQuestion:
    registered = registered_answer.Registered.read(registered_answer.EXPERIMENT, SCALE)
    sweep = root / "multirun" / registered.experiment / SCALE
    cells = collect_sweep(sweep) if sweep.is_dir() else {}
    return OpenQuestion(registered, registered_answer.measure(registered, cells) if cells else None)


def section(question: OpenQuestion) -> list[str]:
    """REPRODUCTION.md's section on the open question."""
    experiment = question.registered.experiment
    lines = ["## Beyond the paper: does transfer help PPO? (Table V)", "",
             "The paper leaves open whether its strategies help learners other than Q-learning. Table V asks it "
             "of Stable-Baselines3's PPO, tuned by Table I's protocol, on the DQN's sensor vector: the 11 rows "
             f"x {question.registered.runs_per_row} seeds at the paper's scale. Its measures and decision rule "
             f"were registered in `conf/experiment/{experiment}.yaml` before its first run: \"transfer helps "
             "PPO\" when the 95 % bootstrap interval of the L_R ratio (with transfer / without) of a strategy's "
             "best N_source lies entirely below 1.", "",
             f"**Answer:** {question.status()}."]
    if question.complete and question.measures.rows:
        lines += ["", *[f"- {row.cell} (best of {row.strategy}): L_R ratio {format_interval(row.loss_ratio)}: "
                        f"{row.words}." for row in question.measures.best.values()]]
        lines += ["", question.split(), "", question.typical_run(), "",
                  f"Every row, its interval and the split with intervals: [{experiment}_answer.md]({experiment}_answer.md)."]
    return lines


def headline(question: OpenQuestion) -> str:
    """The README headline's line on the open question."""
    line = f"**Beyond the paper: does transfer help PPO?** (Table V, registered before its runs): {question.status()}."
    return " ".join(part for part in (line, question.split(), question.typical_run()) if part)
