"""Where a study was registered: the commit that added its registration file."""

from __future__ import annotations

import subprocess
from pathlib import Path


def added_in(path: Path) -> str:
    """The commit that added ``path`` (its pre-registration), e.g. 'abc1234 (2025-01-31)', if git
    knows it; 'its first commit' otherwise (a copy without history)."""
    try:
        out = subprocess.run(["git", "log", "--diff-filter=A", "--format=%h (%cs)", "--", str(path)],
                             cwd=path.parent, capture_output=True, text=True, timeout=30).stdout.split()
    except (OSError, subprocess.SubprocessError):
        return "its first commit"
    return " ".join(out[-2:]) if out else "its first commit"
