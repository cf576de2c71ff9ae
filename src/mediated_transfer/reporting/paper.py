"""The paper's published numbers (Tables II-IV), as data: paper_tables.csv, transcribed from the
paper's text. Reports show them next to the measured values; nothing here is computed.

Columns: table (II, III, IV), representation, scheme ("without transfer", "regular transfer",
"scaffolded transfer"), n_source, reward_loss_mean, reward_loss_sem, time_to_threshold_steps
(approximate in the paper, "~"; empty when the threshold was never reached).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources

SCHEMES = {"none": "without transfer", "regular": "regular transfer", "scaffolded": "scaffolded transfer"}
"""The paper's name of each strategy."""
STRATEGY_OF_SCHEME = {v: k for k, v in SCHEMES.items()}


def scheme(strategy: str) -> str:
    """How a report names a strategy: the paper's words for its own, a plugin's by its name."""
    return SCHEMES.get(strategy, strategy)


@dataclass(frozen=True)
class PaperRow:
    table: str
    representation: str
    strategy: str
    n_source: int
    reward_loss_mean: float
    reward_loss_sem: float
    time_to_threshold: int | None
    """Approximate in the paper; None: never reached ("-")."""

    @property
    def cell(self) -> str:
        return f"{self.strategy}_{self.n_source}"


def paper_rows(table: str | None) -> list[PaperRow]:
    """The rows of one of the paper's tables ("II", "III" or "IV"), in the paper's order; none
    for a table the paper does not have (``report.paper_table: null``)."""
    if table is None:
        return []
    rows = [r for r in _all_rows() if r.table == table]
    if not rows:
        known = sorted({r.table for r in _all_rows()})
        raise ValueError(f"report.paper_table={table!r} is unknown; allowed: {', '.join(known)}")
    return rows


def _all_rows() -> list[PaperRow]:
    text = resources.files(__package__).joinpath("paper_tables.csv").read_text()
    rows = []
    for record in csv.DictReader(text.splitlines()):
        threshold = record["time_to_threshold_steps"].strip()
        rows.append(PaperRow(
            table=record["table"],
            representation=record["representation"],
            strategy=STRATEGY_OF_SCHEME[record["scheme"]],
            n_source=int(record["n_source"]),
            reward_loss_mean=float(record["reward_loss_mean"]),
            reward_loss_sem=float(record["reward_loss_sem"]),
            time_to_threshold=int(threshold) if threshold else None,
        ))
    return rows
