"""The one judge of a stored run: is it reused, recomputed, set aside, or reported stale?

Every place that meets a run folder asks here: the sweep before its jobs start (preflight) and
each job (sweep/job.py), the launchers (local, SLURM: slurm/jobs.py ``is_finished``) and the
reports (reporting/collect.py, and ``stale`` for the runs they count as stale). What each of
them then does differs (the job renames a damaged run's files, the report leaves it out, the
launcher submits its job), but the verdict is this module's, so they cannot disagree.

- **reuse**: the folder's run, whole and current.
- **recompute**: nothing is stored there, or the run is stale and ``rerun_stale`` asks for it.
- **set aside**: the record is damaged (stored/check.py), another cell's or seed's run was moved
  or copied there (``check_place``), or its recorded config is not a run this code can read.
- **reported stale**: computed by other code (provenance.staleness), reused as it is and said so.

A finished run of another configuration than the one wanted there is none of these: two sweeps
share the folder, and ``ConfigError`` refuses it (naming every difference).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..config.compose import ConfigError
from ..config.spec import comparable, differences, run_spec, spec_from_dict, spec_values
from ..results import RESULT_FILE, DamagedResult, RunResult
from ..stored.check import check_place
from . import staleness

if TYPE_CHECKING:
    from ..run import RunSpec

REUSE, RECOMPUTE, SET_ASIDE, STALE = "reuse", "recompute", "set aside", "reported stale"


@dataclass(frozen=True)
class Verdict:
    """What becomes of the run stored in ``folder``: ``action``, one of the four above, and
    ``reason``, its one line (None for a current run, or for an empty folder). Both digest the
    run's code when it is whole; ``kept``, ``found`` and ``damaged`` do so only when they must."""

    folder: Path
    result: RunResult | None
    """The stored run, when it is the folder's and can be used (reuse, reported stale)."""
    damaged: DamagedResult | None
    """Why it is set aside (the file, what is wrong)."""
    rerun_stale: bool

    @functools.cached_property
    def stale(self) -> str | None:
        """Why the stored run no longer matches the code; None if current (or nothing usable).
        Computed when first asked: digesting a run's code takes a while (imports and a walk
        of its closure), and a report, or a launcher that keeps stale runs, need not know."""
        return None if self.result is None else stale(self.result)

    @property
    def kept(self) -> bool:
        """Whether a sweep keeps the stored run as it is (reuse or reported stale)."""
        return self.result is not None and not (self.rerun_stale and self.stale is not None)

    @property
    def found(self) -> bool:
        """Whether anything was stored there (a run, or what is left of one)."""
        return self.result is not None or self.damaged is not None

    @property
    def action(self) -> str:
        if self.damaged is not None:
            return SET_ASIDE
        if not self.kept:
            return RECOMPUTE
        return REUSE if self.stale is None else STALE

    @property
    def reason(self) -> str | None:
        return str(self.damaged) if self.damaged is not None else self.stale


def judge(folder: str | os.PathLike, want: "RunSpec | None" = None, *, place: tuple[str, int | str] | None = None,
          rerun_stale: bool = False) -> Verdict:
    """The verdict on the run stored in ``folder``. ``want``: the run the caller would compute
    there (its config is compared too); else ``place``: the folder's table cell and seed (the run
    there must be theirs); neither: any whole run will do. ConfigError (one line) if the folder
    holds a finished run of another configuration than ``want``."""
    folder = Path(folder)
    if not RunResult.exists(folder):
        return Verdict(folder, None, None, rerun_stale)
    try:
        result = RunResult.read(folder)
        if want is not None:
            check_same_run(result, want, folder)
        elif place is not None:
            check_place(folder, result, *place)
    except DamagedResult as damaged:
        return Verdict(folder, None, damaged, rerun_stale)
    return Verdict(folder, result, None, rerun_stale)


def stale(result: RunResult) -> str | None:
    """Why ``result`` no longer matches the code (provenance.staleness); None if current."""
    if result.config:
        spec = spec_from_dict(spec_values(result.config))
    else:  # its code is still known by its options' names (the built-ins')
        spec = spec_from_dict({"algorithm": result.algorithm, "representation": result.representation,
                               "strategy": result.strategy, "n_source": result.n_source})
    return staleness(result.code, result.results_format, spec)


def check_same_run(result: RunResult, spec: "RunSpec", folder: Path) -> None:
    """ConfigError naming every difference if ``folder``'s result was computed from another config;
    DamagedResult if it is another cell's or seed's run (moved or copied there) or its recorded
    config cannot be read as a run."""
    # Another cell's or seed's run is not this folder's run at all: set aside, not refused.
    check_place(folder, result, f"{spec.strategy}_{spec.n_source}", spec.seed)
    # A folder is named after the cell, the seed and the swept keys; a result computed with
    # other values there (e.g. an override excluded from the folder name) must not be passed
    # off as this run's.
    if not result.config:
        raise ConfigError(f"{folder / RESULT_FILE} has no recorded config; delete the folder to rerun it")
    try:
        stored = comparable(run_spec(result.config))
    except ConfigError as error:
        # e.g. a value earlier code wrote as null (an infinity before it was written as "inf"):
        # the run cannot be identified, so it cannot be reused; it is set aside, not refused.
        raise DamagedResult(folder / RESULT_FILE, f"its recorded config is not a run this code "
                                                  f"can read ({error})") from None
    wanted = comparable(spec)
    # A key added since the run was made is missing from its record: it ran with what the key's
    # default keeps (a new key's default keeps the old behaviour), not with another value. Its
    # code digest differs anyway, so the run shows as stale (rerun_stale=true recomputes it).
    for group in ("algorithm_params", "representation_params", "strategy_params", "world"):
        if isinstance(stored.get(group), dict) and isinstance(wanted.get(group), dict):
            stored[group] = {**{k: v for k, v in wanted[group].items() if k not in stored[group]},
                             **stored[group]}
    detail = differences(stored, wanted)
    if detail:
        raise ConfigError(
            f"{folder} holds a finished run of another configuration ({detail}). Use another "
            "paths.root, or delete the folder to recompute it."
        )
