"""Carry results over a change of the code they executed, or refuse to: one command, whose
evidence it computes itself.

    python -m mediated_transfer.provenance.carry_over [--accept "WHY"] [--retake] [--kind KEY]
    make carry-over

For every run kind whose code digest differs from the one fingerprints.json records (the code
the kind executes changed), it runs the kind's standing short run (standing.py) and compares its
fingerprint with the recorded one:

- the same: the new code computes bit for bit what the old computed. One step of
  translations.json maps each such kind's old digest to today's,
  so results of the old code read current, and fingerprints.json records today's digest.
- another: nothing is written for that kind, and the command exits 1 naming it. If the change of
  behaviour is meant, ``--accept "WHY"`` records the new fingerprint instead (with WHY): results
  of the old code then read stale, which is right.

A kind without a fingerprint (a new learner, representation or plugin strategy) gets one.
``--retake`` runs every kind, moved or not: after editing standing.py (which no digest covers),
or to check that this machine reproduces the fingerprints; a kind whose digest did not move but
whose fingerprint differs is refused (or, with ``--accept``, recorded) the same way.
"""

from __future__ import annotations

import argparse
import contextlib
import platform
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from . import SCHEME, _dirty, _git, append_translation, library_versions
from . import fingerprints as record
from . import standing


TAKEN_WITHOUT_CHOICES = frozenset({"aa160fd290814cbdb13f94283846f0fd15292284",
                                    "aa5221465baa6409cc490d60711d4bc4d985dd6a"})
"""Commits at which the fingerprints of lockstep and own-loop (SB3) kinds were taken while those
loops recorded no episode choices (``choices`` None; the one run loop records them since). Such
an entry is compared with ``choices`` left out (fed as None, what those runs had: the old hash
exactly); when it reproduces, the full fingerprint is recorded, and the translation says so."""
LEFT_OUT = ("choices",)


def _taken_without_choices(kind, entry) -> bool:
    from ..learners.factory import own_run_loop

    return (entry is not None and entry.commit in TAKEN_WITHOUT_CHOICES
            and (kind.lockstep or own_run_loop(kind.algorithm) is not None))


@dataclass
class Outcome:
    carried: list[str] = field(default_factory=list)
    """Kinds whose digest moved and whose standing run reproduced its fingerprint."""
    reproduced: list[str] = field(default_factory=list)
    """Kinds run although their digest did not move (``retake``), fingerprint reproduced."""
    recorded: list[str] = field(default_factory=list)
    """Kinds whose fingerprint was recorded anew: new kinds, and accepted changes."""
    refused: dict[str, str] = field(default_factory=dict)
    """Kinds whose standing run computes something else now (or could not run): one line each."""
    left_out: list[str] = field(default_factory=list)
    """Carried kinds compared with ``choices`` left out (TAKEN_WITHOUT_CHOICES)."""
    step: dict | None = None
    """The translations.json step written, if any."""


def carry_over(accept: str | None = None, retake: bool = False, only: Sequence[str] = (),
               say: Callable[[str], None] = print) -> Outcome:
    """Run the standing runs of the kinds that need it and write what they show (module doc)."""
    kinds = standing.kinds()
    unknown = [key for key in only if key not in kinds]
    if unknown:
        raise ValueError(f"no such run kind: {', '.join(unknown)} (kinds look like {next(iter(kinds))})")
    entries = record.load()
    for key in sorted(set(entries) - set(kinds)):
        say(f"{key}: in fingerprints.json but no longer a run kind here (left as it is)")
    say(f"code digests of {len(only or kinds)} run kinds ...")
    now = {key: kinds[key].digest() for key in (only or kinds)}
    todo = [key for key in now if retake or key not in entries or entries[key].digest != now[key]]
    if not todo:
        say(f"all {len(now)} run kinds' fingerprints were taken at their current code digest: nothing to run")
        return Outcome()
    say(f"standing runs of {len(todo)} of {len(now)} run kinds ({_reasons(todo, entries, now)}):")
    taken = _take(todo, kinds, entries, say)

    outcome, commit, dirty, versions = Outcome(), _git("rev-parse", "HEAD"), _dirty(), _versions()
    updated = dict(entries)
    for key, taken_key in taken.items():
        old = entries.get(key)
        found, compared = (taken_key, taken_key) if not isinstance(taken_key, tuple) else taken_key
        if isinstance(found, Exception):
            outcome.refused[key] = f"{key}: its standing run failed ({_one_line(found)})"
        elif old is not None and compared == old.fingerprint:
            (outcome.carried if old.digest != now[key] else outcome.reproduced).append(key)
            if compared != found:
                outcome.left_out.append(key)
            updated[key] = replace(old, digest=now[key], fingerprint=found, commit=commit, dirty=dirty,
                                   versions=versions)
        elif old is None or accept:
            outcome.recorded.append(key)
            updated[key] = record.Entry(now[key], found, commit, dirty, versions, accept if old else None)
        else:
            outcome.refused[key] = (f"{key}: computes something else now (fingerprint {found[:12]} at digest "
                                    f"{now[key]}; recorded {old.fingerprint[:12]} at digest {old.digest}, "
                                    f"commit {str(old.commit)[:10]}, {old.versions})")
    if outcome.carried:
        outcome.step = _step(outcome.carried, entries, now, commit, dirty, versions, outcome.left_out)
        append_translation(outcome.step)
    if updated != entries:
        record.save(updated)
    _summarise(outcome, accept, say)
    return outcome


def _take(todo: list[str], kinds: dict, entries: dict, say) -> dict[str, str | tuple | Exception]:
    """Each kind's fingerprint now (the exception of a run that raised), with a line per kind; for
    a kind taken without choices, (full fingerprint, the one with choices left out)."""
    taken: dict[str, str | tuple | Exception] = {}
    with tempfile.TemporaryDirectory(prefix="standing-cache-") as cache:  # C, clustered once per size
        for i, key in enumerate(todo, 1):
            start = time.perf_counter()
            old = entries.get(key)
            try:
                if _taken_without_choices(kinds[key], old):
                    found = standing.standing_fingerprints(kinds[key], cache, (LEFT_OUT,))
                    taken[key] = (found[()], found[LEFT_OUT])
                else:
                    taken[key] = standing.standing_fingerprint(kinds[key], cache)
            except Exception as error:  # noqa: BLE001 - named with its kind, the others still run
                taken[key] = error
            compared = taken[key][1] if isinstance(taken[key], tuple) else taken[key]
            verdict = ("FAILED" if isinstance(taken[key], Exception) else "new fingerprint" if old is None
                       else "OTHER fingerprint" if compared != old.fingerprint
                       else "same fingerprint" + (" (choices left out)" if isinstance(taken[key], tuple) else ""))
            say(f"  [{i:>{len(str(len(todo)))}}/{len(todo)}] {key}: {verdict} ({time.perf_counter() - start:.1f} s)")
    return taken


def _step(carried: list[str], entries: dict, now: dict, commit: str | None, dirty: bool | None,
          versions: str, left_out: Sequence[str] = ()) -> dict:
    """The translations.json step of the carried kinds: old digest -> today's, and the evidence."""
    before = sorted({entries[key].commit or "unknown" for key in carried})
    code = (f"commit {commit[:10]}{' with uncommitted changes' if dirty else ''}" if commit
            else "a tree outside git")
    why = (f"The standing short runs (provenance/standing.py) of these {len(carried)} run kinds, whose executed "
           f"code changed, reproduced bit for bit the fingerprints recorded at their earlier digests (commit "
           f"{', '.join(c[:10] for c in before)}) with the code of {code}: the same curves, success rates, "
           f"results, episode choices and trained learner states. Computed by carry_over on {versions}.")
    if left_out:
        why += (f" Of these, {len(left_out)} ({', '.join(sorted(left_out))}) were compared with their episode "
                "choices left out (fed as None, what their loops recorded when the fingerprint was taken): "
                "their loops (lockstep, own loop) record choices now, computed beside the same run; every "
                "other field and the learner state reproduced bit for bit, and their full fingerprints are "
                "recorded now.")
    return {"why": why, "from_commit": before[0] if len(before) == 1 else before, "to_commit": commit,
            "to_scheme": SCHEME, "map": {key: {entries[key].digest: now[key]} for key in sorted(carried)}}


def _reasons(todo: list[str], entries: dict, now: dict) -> str:
    new = sum(key not in entries for key in todo)
    moved = sum(key in entries and entries[key].digest != now[key] for key in todo)
    parts = [f"{moved} with moved code digests" if moved else "", f"{new} new" if new else "",
             f"{len(todo) - new - moved} retaken" if len(todo) - new - moved else ""]
    return ", ".join(p for p in parts if p)


def _summarise(outcome: Outcome, accept: str | None, say) -> None:
    if outcome.carried:
        say(f"carried over: {len(outcome.carried)} run kinds (a step of translations.json maps their old "
            "digests to today's: their results read current)")
    if outcome.reproduced:
        say(f"reproduced: {len(outcome.reproduced)} run kinds at unchanged digests")
    if outcome.recorded:
        say(f"recorded: {len(outcome.recorded)} new fingerprints" + (f" (accepted: {accept})" if accept else ""))
    if outcome.refused:
        say(f"refused: {len(outcome.refused)} run kinds, nothing written for them:")
        for line in outcome.refused.values():
            say(f"  {line}")
        say('if the change of behaviour is meant, run again with --accept "WHY" (their committed runs will '
            "read stale); otherwise find what the change altered")


def _one_line(error: Exception) -> str:
    text = str(error).strip()
    return f"{type(error).__name__}: {text.splitlines()[0]}" if text else type(error).__name__


def _versions() -> str:
    """Python, the libraries that compute a run, and the machine (its processor too: torch picks
    its kernels by it): what a fingerprint also depends on."""
    return ", ".join([f"{name} {version}" for name, version in library_versions().items() if version]
                     + [platform.machine() or "unknown machine", processor()])


def processor() -> str:
    """The processor's model name and widest vector instructions (Linux: /proc/cpuinfo; a virtual
    machine's name may say little), else what ``platform`` says."""
    with contextlib.suppress(OSError):
        info = dict(line.split(":", 1) for line in Path("/proc/cpuinfo").read_text().splitlines()
                    if ":" in line and line.split(":", 1)[0].strip() in ("model name", "flags"))
        info = {key.strip(): value.strip() for key, value in info.items()}
        flags = set(info.get("flags", "").split())
        widest = next((name for name in ("avx512f", "avx2", "avx", "sse4_2") if name in flags), "")
        return " ".join(part for part in (info.get("model name", ""), widest) if part) or "unknown processor"
    return platform.processor() or "unknown processor"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--accept", metavar="WHY", help="record the new fingerprints of kinds that compute "
                        "something else now: the change of behaviour is meant, and WHY says what it is")
    parser.add_argument("--retake", action="store_true", help="run every kind, also those whose code did not move")
    parser.add_argument("--kind", action="append", default=[], metavar="KEY",
                        help="only this run kind (e.g. linear_q/rbf/regular/lockstep); repeatable")
    args = parser.parse_args(argv)
    if args.accept is not None and not args.accept.strip():
        parser.error("--accept needs a reason: what the change of behaviour is")
    try:
        outcome = carry_over(args.accept, args.retake, args.kind, say=lambda line: print(line, flush=True))
    except ValueError as error:
        parser.error(str(error))
    return 1 if outcome.refused else 0


if __name__ == "__main__":
    sys.exit(main())
