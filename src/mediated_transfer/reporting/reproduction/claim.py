"""What a claim of the paper is in the report: its words, the rows it covers, and its parts, each
decided by a rule of verdicts.py; the claim's verdict follows from its parts' (R6)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..verdicts import Part, claim_verdict


@dataclass
class Claim:
    """One of the paper's six headline claims, split into its parts (verdicts.py)."""

    text: str
    """The claim as NOTES.md sums it up."""
    short: str
    """The same in a few words, for the README."""
    source: str
    """The paper's own words the parts and rows are read from, with where they stand."""
    scope: str
    """Which learners and rows the claim covers, and why (R7)."""
    parts: list[Part]
    shown: list[str] = field(default_factory=list)
    """Rows shown for information, not counted, and notes."""

    @property
    def verdict(self) -> str:
        return claim_verdict([(p.kind, p.verdict) for p in self.parts])

    def parts_summary(self) -> str:
        """Each part's name and verdict, e.g. 'direction: partly; size: not reproduced'."""
        return "; ".join(f"{p.name}: {p.verdict}" for p in self.parts)

    def sentence(self) -> str:
        """The claim's verdict in one sentence, each part with its tally and evidence."""
        said = "; ".join(f"{p.statement}: {p.verdict} ({p.tally()}{'; ' + p.evidence if p.evidence else ''})"
                         for p in self.parts)
        return f"{self.verdict.capitalize()}. {said[0].upper()}{said[1:]}."
