"""Start-up: re-running a finished sweep (a skip) against computing it, whole processes.

A finished sweep run again is answered from its stored results (sweep/answered.py) without
Hydra's launch or MLflow's client. Measured here in one run, in a temporary folder: a smoke
sweep of one run computed once, then skipped ``repeats`` times; the figure is the skip's median
wall time (aim: under 1.5 s on 2 free cores) and its ratio to the first, computing, command.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time

COMMAND = ["-m", "mediated_transfer", "-m", "scale=smoke", "scale.seeds=1", "paths.root=."]


def _timed(cwd: str) -> tuple[float, str]:
    start = time.perf_counter()
    out = subprocess.run([sys.executable, *COMMAND], cwd=cwd, capture_output=True, text=True, timeout=600)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(COMMAND)} failed: {out.stderr.strip().splitlines()[-1:]}")
    return time.perf_counter() - start, out.stdout + out.stderr


def run(repeats: int | None = None) -> dict[str, float]:
    repeats = repeats or 5
    with tempfile.TemporaryDirectory() as folder:
        computed, _ = _timed(folder)
        skips = []
        for _ in range(repeats):
            seconds, output = _timed(folder)
            if "found, skipped" not in output:
                raise RuntimeError(f"the second command did not skip its finished run:\n{output}")
            skips.append(seconds)
    skip = statistics.median(skips)
    print(f"  computing a smoke run: {computed:.2f} s; skipping it: {skip:.2f} s "
          f"(median of {repeats}; aim < 1.5 s); skip / compute = {skip / computed:.2f}")
    return {"compute_s": computed, "skip_s": skip, "skip_over_compute": skip / computed}
