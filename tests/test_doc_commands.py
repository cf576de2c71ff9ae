"""Every ```bash block of README.md and docs/*.md runs as written, so a documented command can no
longer rot (issue 44). The Python blocks run in test_readme.py.

A block runs in bash (``-e``: its first failing command fails it) from a folder of its own that
holds ``examples/`` as the repository's, with shims first on PATH (tests/doc_shims.py):
``python -m mediated_transfer...`` through a fork server that imported the package once (a
command costs its work, not a second of imports), at smoke scale, one seed per cell, in the
test's folder; ``make`` as ``make -n`` (what each target would run: a make target builds a
virtual environment or runs hours of sweeps); ``pip install`` checks that the extras and files it
names exist. Placeholders (``<partition>``) become words, and ``/tmp/`` the test's folder. A
block that runs passes if every command exits 0 and each ``--out`` file it names is written.

The blocks in DRY are too long for CI, need what it lacks, or run what another test runs end to
end (the suite has a time budget); their run commands are checked as the entry point checks a
command before any work (Hydra's parse; the configs of its jobs composed and checked, one per
value it sweeps over; its plugins built), their reporting commands compose and read an empty
run folder, other modules print their ``--help``. Each entry names a text that must occur in
exactly one block, and why.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

DRY = {
    ("README.md", "experiment=table2_rbf scale=quick      # a whole table"): "a whole table's sweep (11 cells)",
    ("README.md", "hydra/launcher=slurm"): "SLURM",
    ("README.md", "cell=custom"): "a plugin's sweep and report: tests/test_extending.py runs them",
    ("docs/configuration.md", "n_source=7"): "three runs: tests/test_run.py runs single runs",
    ("docs/curricula.md", "auto_curricula"): "curriculum runs: tests/test_curricula.py runs them",
    ("docs/extending.md", "file://examples/plugins"): "plugin runs: tests/test_extending.py runs them",
    ("docs/extending.md", "cell=custom"): "a plugin's sweep and report: tests/test_extending.py runs them",
    ("docs/extending.md", "env=rake"): "a world's sweep and GIF: tests/test_worlds.py runs them",
    ("docs/results.md", "hydra.launcher.n_jobs=1"): "PPO runs: tests/test_sb3.py runs them",
    ("docs/configuration.md", "--variant"): "two whole-table sweeps and their comparison",
    ("docs/extending.md", "algorithm=tabular_q"): "a whole table (tests/test_extending.py runs a cell of it)",
    ("docs/extending.md", "env=straight_stick"): "a whole table (tests/test_extending.py runs a cell of it)",
    ("docs/history.md", "--variant tuned=linear_q_rbf_round1"): "paper scale",
    ("docs/history.md", "for v in"): "paper scale, 80 runs",
    ("docs/history.md", "name=table3_fsr_tuning_seeds"): "20 seeds per cell",
    ("docs/history.md", "name=fsr_eps_check"): "20 seeds per cell",
    ("docs/learners.md", "algorithm=sb3_ppo scale=quick     # a variant"): "a whole table of PPO runs",
    ("docs/results.md", "experiment=table2_rbf scale=paper"): "paper scale",
    ("docs/results.md", "make reproduction"): "paper scale",
    ("docs/results.md", "transfer_answer --experiment table4_dnn"):
        "reads the committed paper-scale runs: tests/test_transfer_answer.py runs it",
    ("docs/sensitivity.md", "make sensitivity"): "the study: 210 runs",
    ("docs/sweeps-and-slurm.md", "a subset"): "a whole table's sweep, in the block of its subset",
    ("docs/sweeps-and-slurm.md", "partition=<partition>"): "SLURM",
    ("docs/sweeps-and-slurm.md", "lockstep.device=cuda"): "a GPU",
}


def _blocks() -> list[tuple[str, int, str]]:
    found = []
    for page in PAGES:
        for i, code in enumerate(re.findall(r"```bash\n(.*?)```", page.read_text(), flags=re.S)):
            found.append((page.relative_to(ROOT).as_posix(), i, code))
    return found


BLOCKS = _blocks()


def _mode(page: str, code: str) -> str:
    return "dry" if any(p == page and text in code for p, text in DRY) else "smoke"


def test_every_dry_entry_names_one_block():
    for (page, text), why in DRY.items():
        matches = [i for p, i, code in BLOCKS if p == page and text in code]
        assert len(matches) == 1, f"DRY entry {page!r} {text!r} ({why}) matches blocks {matches}"


@pytest.fixture(scope="session")
def shims(tmp_path_factory) -> Iterator[tuple[Path, str]]:
    """The shims' folder, and the address of the fork server that runs the package's commands."""
    folder = tmp_path_factory.mktemp("shims")
    here = str(Path(__file__).parent)
    python = folder / "python"
    python.write_text(f"#!{sys.executable}\nimport sys\nsys.path.insert(0, {here!r})\n"
                      "import doc_shims\nsys.exit(doc_shims.main())\n")
    make = shutil.which("make")  # the real one: the shim is first on the blocks' PATH
    (folder / "make").write_text(f"#!/bin/sh\nexec {make} -n -C {ROOT} \"$@\"\n")
    (folder / "pip").write_text(f"#!{sys.executable}\nimport sys\nsys.path.insert(0, {here!r})\n"
                                "from test_doc_commands import check_pip\nsys.exit(check_pip(sys.argv[1:]))\n")
    for shim in folder.iterdir():
        shim.chmod(shim.stat().st_mode | stat.S_IXUSR)
    address = str(folder / "server.sock")
    server = subprocess.Popen([sys.executable, str(Path(here) / "doc_shims.py"), "serve", address],
                              stdout=subprocess.PIPE, text=True, env={**os.environ, "DOC_PYTHONPATH": ""})
    try:
        assert server.stdout.readline().strip() == "ready", "the fork server did not start"
        yield folder, address
    finally:
        server.terminate()
        server.wait()


def check_pip(args: list[str]) -> int:
    """``pip install -e <path>[extras] [-c file]``: the path, its extras and the file exist."""
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    for flag, value in zip(args, args[1:]):
        if flag == "-e":
            path, _, wanted = value.partition("[")
            missing = [e for e in wanted.rstrip("]").split(",") if e and e not in extras]
            if not (ROOT / path / "pyproject.toml").is_file() or missing:
                print(f"pip install -e {value}: no project there, or no extras {missing}", file=sys.stderr)
                return 1
        if flag == "-c" and not (ROOT / value).is_file():
            print(f"pip install -c {value}: no such file", file=sys.stderr)
            return 1
    return 0 if args[:1] == ["install"] else 1


@pytest.mark.slow
@pytest.mark.parametrize("page, index, code", BLOCKS, ids=[f"{p}:block{i}" for p, i, _ in BLOCKS])
def test_documented_block_runs(page, index, code, shims, tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    (work / "examples").symlink_to(ROOT / "examples")
    (work / "reports").mkdir()
    mode = _mode(page, code)
    code = re.sub(r"<(\w+)>", r"\1", code).replace("/tmp/", f"{tmp_path}/")
    if mode == "smoke":  # a run folder named after its scale, as the smoke runs write it
        code = re.sub(r"/(paper|quick)/", "/smoke/", code)
    folder, server = shims
    env = {**os.environ, "PATH": f"{folder}{os.pathsep}{os.environ['PATH']}", "DOC_MODE": mode, "DOC_SERVER": server,
           "DOC_ROOT": str(tmp_path / "root"), "DOC_PYTHON": sys.executable,
           "DOC_PYTHONPATH": os.environ.get("PYTHONPATH", ""), "PYTHONPATH": ""}
    ran = subprocess.run(["bash", "-e", "-c", code], cwd=work, env=env, capture_output=True, text=True, timeout=300)
    assert ran.returncode == 0, f"{page} block {index} ({mode}) failed:\n{ran.stderr[-3000:]}"
    if mode == "smoke":  # and wrote what it says it writes
        for out in re.findall(r"--out (\S+)", code):
            assert (work / out).is_file(), f"{page} block {index}: no {out} written"
