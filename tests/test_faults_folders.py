"""Two faults of shared folders, at smoke scale in temporary folders:

- two sweeps of different configurations into one folder at once: the run folder one of them is
  computing is named, with both configurations' differing keys, by the other, which ends
  non-zero (a claim for the same configuration stays a quiet skip);
- a run folder holding another cell's run (moved or copied there): set aside like a damaged run,
  recomputed by the sweep, left out of the report, which names it.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mediated_transfer.reporting.__main__ import main as reporting_main
from mediated_transfer.results import CURVE_FILE, RESULT_FILE, RunResult
from mediated_transfer.slurm.jobs import is_finished
from mediated_transfer.stored.aside import SUFFIX

from .test_sweep import _run_cli, source_cache  # noqa: F401 - source_cache: the session's fixture

pytestmark = pytest.mark.slow

# Sweep A, in a process of its own: its first run waits, its folder claimed, until told to go on.
_HELD_SWEEP = """
import sys, time
from pathlib import Path
import mediated_transfer.run as run

computing, go = Path(sys.argv[1]), Path(sys.argv[2])
real = run.execute_run

def held(*args, **kwargs):
    computing.touch()
    while not go.exists():
        time.sleep(0.05)
    return real(*args, **kwargs)

run.execute_run = held
from mediated_transfer.app import cli
cli(sys.argv[3:])
"""


def _wait_for(path: Path, process: subprocess.Popen, timeout: float = 120) -> None:
    deadline = time.time() + timeout
    while not path.exists():
        if process.poll() is not None:
            raise AssertionError(f"the held sweep ended first: {process.communicate()}")
        assert time.time() < deadline, "the held sweep never started its run"
        time.sleep(0.05)


@pytest.mark.slow
def test_two_sweeps_of_different_configurations_in_one_folder_at_once_are_named(tmp_path, capsys):
    shared = tmp_path / "shared"  # one paths.sweep_dir for two experiments: the same run folders
    common = ["cell=none_0", "seed=0", "scale=smoke", "tracking=none", "hydra/launcher=basic",
              f"paths.root={tmp_path}", f"paths.sweep_dir={shared}"]
    folder = shared / "none_0" / "seed=0"
    computing, go = tmp_path / "computing", tmp_path / "go"
    held = subprocess.Popen([sys.executable, "-c", _HELD_SWEEP, str(computing), str(go),
                             "-m", "experiment=table2_rbf", *common],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        _wait_for(computing, held)  # sweep A computes none_0 seed=0, its folder claimed

        # The same configuration (a second launch of sweep A): the supported case, a quiet skip.
        _run_cli("-m", "experiment=table2_rbf", *common)
        out = capsys.readouterr().out
        assert "none_0 seed=0: being computed by another process, skipped" in out
        assert "another configuration" not in out

        # Another configuration (sweep B, FSR) into the same folder: named, and B ends non-zero.
        with pytest.raises(SystemExit) as ended:
            _run_cli("-m", "experiment=table3_fsr", *common)
        assert ended.value.code not in (0, None)
        out, err = capsys.readouterr()
        said = [line for line in (out + err).splitlines() if "for another configuration" in line]
        assert said, out + err
        line = said[-1]
        assert line.startswith(f"{folder}: being computed by another process (pid {held.pid}, sweep table2_rbf)")
        assert "representation: the other 'rbf', this one 'fsr'" in line
        assert "algorithm_params.lambda_: the other" in line
        assert "being computed by another process, skipped" not in out
        assert "Traceback" not in err
    finally:
        go.touch()
        output, _ = held.communicate(timeout=120)
    assert held.returncode == 0, output  # A met no busy folder: its run is its own
    assert RunResult.read(folder).representation == "rbf"
    assert (folder / ".claim").read_text() == ""  # a free claim records nobody


def _args(root: Path, cache: Path) -> list[str]:
    return ["experiment=table3_fsr", "scale=smoke", "tracking=none", f"paths.root={root}", f"paths.cache_dir={cache}"]


@pytest.mark.slow
def test_a_run_folder_holding_another_cells_run_is_set_aside_recomputed_and_left_out(tmp_path, source_cache,
                                                                                     capsys):
    root = tmp_path
    sweep = ["-m", "cell=none_0,regular_1", "seed=0", "hydra/launcher=basic", *_args(root, source_cache)]
    _run_cli(*sweep)
    sweep_dir = root / "multirun" / "table3_fsr" / "smoke"
    folder, other = sweep_dir / "none_0" / "seed=0", sweep_dir / "regular_1" / "seed=0"
    own = json.loads((folder / RESULT_FILE).read_text())
    for name in (RESULT_FILE, CURVE_FILE):  # regular_1's run copied into none_0's folder
        shutil.copy(other / name, folder / name)
    copied = (folder / RESULT_FILE).read_bytes()
    untouched = (other / RESULT_FILE).stat().st_mtime_ns
    capsys.readouterr()
    said = (f"{folder / RESULT_FILE}: holds the run regular_1 seed=0, not this folder's none_0 seed=0: "
            "moved or copied here")

    # The report leaves it out and names it (before: "the folder does not match its content").
    assert reporting_main(_args(root, source_cache)) == 0
    out, err = capsys.readouterr()
    assert "table3_fsr: 1 run (1 damaged left out) -> " in out
    assert [line.strip() for line in err.splitlines() if "left out: " in line] == [f"left out: {said}"]
    assert not is_finished(folder, rerun_stale=False, place=("none_0", 0))  # the launchers compute it
    assert is_finished(other, rerun_stale=False, place=("regular_1", 0))

    # The sweep sets it aside and computes the folder's own run (before: refused in preflight).
    _run_cli(*sweep)
    aside = {p.name.split(SUFFIX)[0]: p for p in folder.iterdir() if SUFFIX in p.name}
    assert {RESULT_FILE, CURVE_FILE} <= set(aside)
    assert aside[RESULT_FILE].read_bytes() == copied  # kept, renamed, not deleted
    again = RunResult.read(folder)
    assert (again.strategy, again.n_source, again.seed) == ("none", 0, 0)
    assert again.mean_reward == own["mean_reward"]
    assert (other / RESULT_FILE).stat().st_mtime_ns == untouched  # regular_1's own run reused
    log = (folder / "mediated_transfer.log").read_text()
    [line] = [line for line in log.splitlines() if "set aside as" in line]
    assert said in line and "computing the run again" in line

    capsys.readouterr()
    assert reporting_main(_args(root, source_cache)) == 0
    out, err = capsys.readouterr()
    assert "table3_fsr: 2 runs -> " in out and "left out" not in err
