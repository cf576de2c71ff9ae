"""What a command writes to fails under it: a full disk (a full quota, a file over the size limit)
and a damaged MLflow store end the command in one line naming the run, the file or store and
what to do (sweep/faults.py), and a warning during a sweep promises only what a rerun does."""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from mediated_transfer import atomic, results
from mediated_transfer.app import run_job
from mediated_transfer.config.compose import compose_config
from mediated_transfer.results import RunResult
from mediated_transfer.sweep import tracking

from .test_sweep import _run_cli
from .test_tracking import _live, fresh_store

SRC = Path(__file__).resolve().parents[1] / "src"


def _mount_point(path: Path) -> str:
    path = path.resolve()
    while not os.path.ismount(path):
        path = path.parent
    return str(path)


# --- a full disk -----------------------------------------------------------------------------------


@pytest.mark.parametrize("sweep", [False, True], ids=["single run", "sweep"])
def test_a_full_disk_stops_the_command_in_one_line_naming_the_run_and_the_file(tmp_path, monkeypatch, capsys,
                                                                              sweep):
    """ENOSPC while a run's result is written (as a full disk raises it: from ``write``, naming
    no file) ends the command with one line: the run as the sweep names it, the file, the file
    system to free, and that a rerun keeps what finished. Before: Hydra's traceback, 25 lines."""

    def full_disk(path, text):  # the real atomic write, whose handle's write fails
        def write(handle):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

        return atomic.atomic_write(path, write)

    monkeypatch.setattr(results, "atomic_write_text", full_disk)
    args = ["scale=smoke", f"paths.root={tmp_path}", "tracking=none", "save_learner=false"]
    if sweep:
        args = ["-m", "experiment=table3_fsr", "cell=none_0", "seed=3", "hydra/launcher=basic", *args]
    with pytest.raises(SystemExit) as stopped:
        _run_cli(*args)
    line = str(stopped.value)
    folder = (tmp_path / "multirun" / "table3_fsr" / "smoke" / "none_0" / "seed=3" if sweep
              else tmp_path / "runs" / "linear_q_rbf" / "smoke" / "none_0" / "seed=0")
    assert line == (f"none_0 seed={3 if sweep else 0}: could not write {folder / 'curve.csv'}: No space left on "
                    f"device (ENOSPC); free space on {_mount_point(tmp_path)}, then run the same command "
                    "again: finished runs are kept")
    err = capsys.readouterr().err  # (in-process runs: a handler of an earlier test's may complain here)
    assert "OSError" not in err and "Error executing job" not in err
    assert not list(folder.glob("*.tmp"))  # nothing half-written left behind


@pytest.mark.slow
def test_a_file_over_the_size_limit_stops_a_parallel_sweep_in_one_line(tmp_path):
    """The same through the default launcher: a pool's worker hands the fault back, and the
    launcher ends the sweep with its one line (``ulimit -f``: EFBIG on the learner's file)."""
    if shutil.which("prlimit") is None:
        pytest.skip("needs prlimit (util-linux)")
    command = ["prlimit", "--fsize=20000", sys.executable, "-m", "mediated_transfer", "-m",
               "experiment=table3_fsr", "scale=smoke", "cell=none_0", "seed=0", "hydra.launcher.n_jobs=1",
               f"paths.root={tmp_path}", "tracking=none"]
    env = {**os.environ, "PYTHONPATH": f"{SRC}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)
    learner = tmp_path / "multirun" / "table3_fsr" / "smoke" / "none_0" / "seed=0" / "learner.npz"
    assert done.returncode == 1
    assert done.stderr.strip().splitlines() == [
        f"none_0 seed=0: could not write {learner}: File too large (EFBIG); raise the file size limit "
        "(ulimit -f) or put paths.root on another file system, then run the same command again: finished "
        "runs are kept"]


def test_a_full_disk_names_the_file_that_hydra_or_a_log_was_writing(tmp_path):
    """Errors of ``write`` and ``close`` name no file: the one being written is found where it
    was open (Hydra's record of a run; /dev/full fails every write with ENOSPC)."""
    from hydra.core.utils import _save_config
    from omegaconf import OmegaConf

    from mediated_transfer.sweep import faults

    if not Path("/dev/full").exists():
        pytest.skip("needs /dev/full")
    with pytest.raises(OSError) as error:
        _save_config(OmegaConf.create({"a": 1}), "full", Path("/dev"))
    fault = faults.disk_full(error.value)
    assert fault is not None and fault.file == "/dev/full"
    assert str(fault).startswith("could not write /dev/full: No space left on device (ENOSPC); free space on /dev")


def test_a_jobs_log_on_a_full_disk_prints_no_traceback_per_line(capsys):
    """Logging reports a line it could not write with a traceback ("--- Logging error ---"),
    for every line; a job's log file (conf/config.yaml) leaves the full disk to the job's line."""
    from mediated_transfer.sweep import faults

    if not Path("/dev/full").exists():
        pytest.skip("needs /dev/full")
    cfg = compose_config(["scale=smoke"], hydra=True)
    assert cfg.hydra.job_logging.handlers.file["class"] == "mediated_transfer.sweep.faults.RunLog"
    logger = logging.getLogger("test_faults_io")
    logger.propagate = False  # to this handler alone (the root's may be an earlier test's job's)
    handler = faults.RunLog("/dev/full")
    logger.addHandler(handler)
    try:
        logger.warning("a progress line")
    finally:
        logger.removeHandler(handler)
        handler.close = lambda: None  # its buffer cannot be flushed either
    assert "Logging error" not in capsys.readouterr().err


# --- a damaged MLflow store ----------------------------------------------------------------------


def _damage(db: Path) -> None:
    """Overwrite the middle half of an SQLite file: its pages, not its header."""
    size = db.stat().st_size
    with open(db, "r+b") as f:
        f.seek(size // 4)
        f.write(b"x" * (size // 2))


@pytest.mark.slow
def test_a_damaged_store_stops_the_command_naming_it_and_the_remedy_that_works(tmp_path):
    """Before: "Could not prepare the runs: DatabaseError: (sqlite3.DatabaseError) database disk
    image is malformed", no store named, and every rerun the same. The remedy the line gives
    (move it aside) works: the same command then logs the finished run into a new store."""
    fresh_store(tmp_path)
    args = ["scale=smoke", f"paths.root={tmp_path}"]
    _run_cli(*args)
    db = tmp_path / "mlflow.db"
    _damage(db)
    with pytest.raises(SystemExit) as stopped:
        _run_cli(*args)
    assert str(stopped.value) == (
        f"Could not prepare the runs: the MLflow store {db} is damaged (database disk image is malformed): "
        f"move it aside (mv {db} {db}.damaged); the runs' results are kept in their folders, and running a "
        "command again logs its finished runs into a new store (make reports adds the cells' summaries); or "
        "run with tracking=none")
    db.rename(f"{db}.damaged")
    # A new process, as a rerun is (this one keeps the damaged file open: MLflow caches its store).
    env = {**os.environ, "PYTHONPATH": f"{SRC}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    rerun = subprocess.run([sys.executable, "-m", "mediated_transfer", *args], capture_output=True, text=True,
                           env=env, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    with contextlib.closing(sqlite3.connect(db)) as store:  # (this process's MLflow holds the old one)
        assert store.execute("SELECT name, status FROM runs").fetchall() == [("none_0/seed=0", "FINISHED")]


def test_a_store_damaged_during_a_sweep_is_named_in_the_warning_without_promising_a_rerun(tmp_path, caplog):
    """A store damaged after the sweep's check: the run computes and writes its result, and the
    warning names the store and its remedy; it used to say "rerunning the sweep logs it",
    which a rerun did not. A finished run found then stops its job in the same line."""
    fresh_store(tmp_path)
    db = tmp_path / "mlflow.db"
    _damage(db)
    cfg = compose_config(["scale=smoke", f"paths.root={tmp_path}", "save_learner=false"])
    folder = tmp_path / "run"
    with caplog.at_level(logging.WARNING, logger="mediated_transfer"):
        run_job(cfg, folder)
    assert RunResult.exists(folder)
    [warning] = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert warning.startswith(f"none_0 seed=0: not followed in MLflow: the MLflow store {db} is damaged "
                              "(database disk image is malformed): move it aside")
    assert "rerunning the sweep logs it" not in warning
    with pytest.raises(Exception, match=f"^none_0 seed=0: the MLflow store {db} is damaged") as stopped:
        run_job(cfg, folder)
    assert type(stopped.value).__name__ == "StoreDamaged"


def test_a_store_damaged_while_a_run_is_followed_is_named_in_the_warning(tmp_path, monkeypatch):
    settings = tracking.TrackingSettings(fresh_store(tmp_path), str(tmp_path / "artifacts"))
    live = _live(settings)

    def malformed(*args, **kwargs):
        raise sqlite3.DatabaseError("database disk image is malformed")

    monkeypatch.setattr(type(live.client), "log_batch", malformed)
    with pytest.warns(RuntimeWarning) as warned:
        live.evaluation(100, 1.0, 0.1)
    [message] = [str(w.message) for w in warned]
    assert message.startswith(f"MLflow stopped following this run, its result is kept: the MLflow store "
                              f"{settings.store} is damaged (database disk image is malformed): move it aside")
    assert "rerunning the sweep logs it" not in message
