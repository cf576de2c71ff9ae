"""Sealing: a checksum for a record written before checksums existed (before issue 38).

Without its checksum a record cannot show an edit of result.json and curve.csv that agree with
each other, so check.py reads a record without one as damaged. The committed runs written before
issue 38 were sealed once, as committed, after reading whole and consistent; a user's own older
runs can be sealed the same way:

    python -m mediated_transfer.stored.seal multirun/table2_rbf

A record is sealed only if it is whole and consistent (check.consistent); its content is kept
as it is and its checksum added. A damaged record is named and left as it is.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..atomic import atomic_write_text
from . import RESULT_FILE
from .check import DamagedResult, consistent
from .codec import CHECKSUM, encode


def seal(folder: str | Path) -> bool:
    """Add a checksum to the record in ``folder`` if it has none; True if it was added.
    DamagedResult if the record is not whole and consistent (then nothing is written)."""
    record = consistent(folder)
    if CHECKSUM in record:
        return False
    text = encode(record)
    if {k: v for k, v in json.loads(text).items() if k != CHECKSUM} != record:
        raise DamagedResult(Path(folder) / RESULT_FILE, "would not read back as it is (not written by "
                                                        "this project's encoder)")
    atomic_write_text(Path(folder) / RESULT_FILE, text)
    return True


def seal_all(paths: list[Path]) -> tuple[int, int, list[DamagedResult]]:
    """Seal every record under ``paths``: (sealed now, sealed before, damaged ones left as they are)."""
    sealed = before = 0
    damaged = []
    for path in paths:
        records = [path / RESULT_FILE] if (path / RESULT_FILE).exists() else sorted(path.rglob(RESULT_FILE))
        for record in records:
            try:
                if seal(record.parent):
                    sealed += 1
                else:
                    before += 1
            except DamagedResult as error:
                damaged.append(error)
    return sealed, before, damaged


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.stored.seal",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("paths", nargs="+", type=Path, help="run folders, or folders to search for result.json")
    args = parser.parse_args(argv)
    missing = [str(p) for p in args.paths if not p.exists()]
    if missing:
        parser.error(f"no such folder: {', '.join(missing)}")
    sealed, before, damaged = seal_all(args.paths)
    for error in damaged:
        print(f"not sealed: {error}", file=sys.stderr)
    print(f"sealed {sealed} record(s); {before} already had a checksum; {len(damaged)} damaged, left as they are")
    return 1 if damaged else 0


if __name__ == "__main__":
    sys.exit(main())
