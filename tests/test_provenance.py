"""Which code computed a result: a run's digest covers exactly the code it executes (the closure
of its loop, learner, representation, strategy and world), so adding options or plugins and
moving files leave results current, and a change makes exactly the runs that execute it stale."""

from __future__ import annotations

import importlib
import json
import platform
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from mediated_transfer.provenance import (LIBRARIES, RESULTS_FORMAT, library_versions, run_digest, run_kind,
                                          staleness, translate)
from mediated_transfer.provenance.standing import builtin_kinds, digests_now
from mediated_transfer.provenance.closure import closure_digest
from mediated_transfer.run import RunSpec

from .optional import DEEP, needs_deep

REPO = Path(__file__).resolve().parents[1]
# The deep learners' kinds where torch is installed (their code imports it: without it their
# closure, and so their digest, is another; docs/reliability.md).
KINDS = ["linear_q/rbf/regular", "linear_q/rbf/scaffolded", "linear_q/fsr/none"] + (
    ["dqn/network/regular", "dqn/network/regular/lockstep", "sb3_ppo/rbf/regular", "sb3_dqn/network/none"]
    if DEEP else [])


def _module(tmp_path, name: str, source: str):
    folder = tmp_path / name
    folder.mkdir()
    (folder / "__init__.py").write_text("")
    (folder / "curricula.py").write_text(textwrap.dedent(source))
    sys.path.insert(0, str(tmp_path))
    try:
        return importlib.import_module(f"{name}.curricula")
    finally:
        sys.path.remove(str(tmp_path))


PLUGIN = textwrap.dedent("""
    import numpy as np

    STEP = 0.5

    def _helper(x):
        return x * STEP

    class Base:
        def report(self, outcome):
            self.last = outcome

    class Outward(Base):
        '''A docstring.'''
        def next_task(self):
            return _helper(self.distance)  # a comment

        def unused(self):
            return 1
""")


def _drive(strategy):
    """What a run loop names of a strategy: a class's methods count when code calls them."""
    strategy.next_task()
    strategy.report(None)


def _digest(module) -> str:
    return closure_digest([_drive, module.Outward])


def test_a_digest_follows_names_not_files_and_ignores_unused_code(tmp_path):
    base = _digest(_module(tmp_path, "plug_a", PLUGIN))
    # The same code in another package (a moved or renamed file), with comments and docstrings
    # changed and unused code added: the same digest.
    moved = PLUGIN.replace("# a comment", "# another").replace("A docstring.", "Other words.") + \
        "\nclass Unused:\n    pass\n\nOTHER = 3\n"
    moved = moved.replace("    def unused(self):\n        return 1\n", "    def unused(self):\n        return 2\n")
    assert _digest(_module(tmp_path, "plug_b", moved)) == base
    # A constant, a helper, a base class's method the run calls: each changes it.
    for old, new in (("STEP = 0.5", "STEP = 0.25"), ("return x * STEP", "return x / STEP"),
                     ("self.last = outcome", "self.last = None")):
        name = f"plug_{abs(hash(new)) % 10**8}"
        assert _digest(_module(tmp_path, name, PLUGIN.replace(old, new))) != base, new


def _digests_of_edited_copy(root, edits: dict[str, tuple[str | None, str]], moves: dict[str, str] | None = None,
                            kinds=KINDS) -> dict[str, str]:
    """The run kinds' digests computed by a copy of src/ and conf/ with its files moved
    (``moves``: old path -> new path) and edited (path -> (old, new) text; (None, text): a new file)."""
    shutil.copytree(REPO / "src", root / "src", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(REPO / "conf", root / "conf")
    for old, new in (moves or {}).items():
        shutil.move(root / old, root / new)
    for path, (old, new) in edits.items():
        file = root / path
        if old is None:
            file.write_text(new)
            continue
        text = file.read_text()
        assert old in text, (path, old)
        file.write_text(text.replace(old, new))
    script = ("import json, sys; from mediated_transfer.provenance.standing import digests_now; "
              "print(json.dumps(digests_now(json.loads(sys.argv[1]))))")
    out = subprocess.run([sys.executable, "-c", script, json.dumps(kinds)], capture_output=True, text=True,
                         env={"PYTHONPATH": str(root / "src"), "PATH": "/usr/bin:/bin"}, cwd=root)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


@pytest.fixture(scope="module")
def current():
    return digests_now(KINDS)


@pytest.mark.slow
def test_adding_an_unused_strategy_or_moving_a_file_leaves_every_run_current(tmp_path, current):
    strategies = "src/mediated_transfer/transfer/strategies.py"
    added = "\n\nclass EasyFirst(RegularTransfer):\n    def _choose(self):\n        return self._unsolved[0]\n"
    edits = {strategies: ("        return self._unsolved[int(self.rng.integers(len(self._unsolved)))]\n\n\nclass Scaff",
                          "        return self._unsolved[int(self.rng.integers(len(self._unsolved)))]\n" + added +
                          "\n\nclass Scaff"),
             "conf/strategy/easy_first.yaml": (None, "_target_: mediated_transfer.transfer.strategies.EasyFirst\n"
                                                     "name: easy_first\n")}
    assert _digests_of_edited_copy(tmp_path / "added", edits) == current
    # The paper's strategies moved to another module (imports and _target_ paths follow).
    edits = {"src/mediated_transfer/transfer/__init__.py": ("from .strategies import", "from .paper import")}
    for name in ("none", "regular", "scaffolded"):
        edits[f"conf/strategy/{name}.yaml"] = ("transfer.strategies.", "transfer.paper.")
    moves = {"src/mediated_transfer/transfer/strategies.py": "src/mediated_transfer/transfer/paper.py"}
    assert _digests_of_edited_copy(tmp_path / "moved", edits, moves) == current


def test_a_change_to_algorithm_2_makes_the_scaffolded_runs_stale_and_no_other(tmp_path, current):
    edits = {"src/mediated_transfer/transfer/strategies.py": ("self._similarity[k] = -np.inf",
                                                             "self._similarity[k] = -1e300")}
    changed = {k for k, v in _digests_of_edited_copy(tmp_path, edits).items() if v != current[k]}
    assert changed == {"linear_q/rbf/scaffolded"}


@pytest.mark.slow
@needs_deep
def test_a_change_to_one_learner_makes_only_its_runs_stale(tmp_path, current):
    edits = {"src/mediated_transfer/learners/dqn_kernels.py": ("self.adam_steps += 1", "self.adam_steps += 2")}
    changed = {k for k, v in _digests_of_edited_copy(tmp_path / "dqn", edits).items() if v != current[k]}
    assert changed == {"dqn/network/regular", "dqn/network/regular/lockstep"}
    # The one loop (a single run is a lockstep group of one) counts for single and lockstep runs alike.
    edits = {"src/mediated_transfer/lockstep/run.py": ("record.step(reward, td)", "record.step(reward + 0, td)")}
    changed = {k for k, v in _digests_of_edited_copy(tmp_path / "lock", edits).items() if v != current[k]}
    assert {"dqn/network/regular", "dqn/network/regular/lockstep", "linear_q/fsr/none"} <= changed
    assert not any(k.startswith("sb3_") for k in changed)  # SB3's own loop does not run it


def test_results_are_current_through_the_translation_steps_and_stale_otherwise():
    spec = RunSpec(strategy="regular", n_source=1)
    now = run_digest(spec)
    assert staleness({"digest": now}, RESULTS_FORMAT, spec) is None
    assert "computed by other code" in staleness({"digest": "0" * 16}, RESULTS_FORMAT, spec)
    assert "results format 1" in staleness({"digest": now}, None, spec)
    # Every built-in kind's digest of the whole-file scheme maps to one of today's, or none.
    assert translate("not-a-digest", run_kind(spec)) == "not-a-digest"


def test_a_plugin_that_cannot_be_imported_makes_its_results_stale_with_the_path():
    spec = RunSpec(strategy="easy_first", strategy_target="nowhere_pkg.EasyFirst", n_source=1)
    why = staleness({"digest": "0" * 16}, RESULTS_FORMAT, spec)
    assert "nowhere_pkg.EasyFirst" in why and "not importable" in why


@needs_deep
def test_every_builtin_kind_has_a_digest():
    kinds = builtin_kinds()
    assert {"linear_q/rbf/scaffolded", "dqn/network/none/lockstep", "sb3_ppo/fsr/regular"} <= set(kinds)
    digests = digests_now(kinds)
    assert len(set(digests.values())) == len(kinds)  # every kind runs other code


def test_a_digest_does_not_depend_on_what_the_process_composed_before():
    """A config composed with a plugin folder on the search path (what a sweep's worker or a
    test did before) leaves every run's digest as a fresh process computes it: the folders
    remembered are process state, not code (found when the suite's order made runs stale)."""
    from mediated_transfer.config.compose import compose_config, search_dirs
    from mediated_transfer.provenance import run_roots

    spec = RunSpec(representation="fsr", strategy="scaffolded", n_source=100)
    compose_config(["tracking=none"])
    assert search_dirs() == []
    before = closure_digest(run_roots(spec))
    try:
        compose_config(["tracking=none", "hydra.searchpath=[pkg://auto_curricula.conf]"])
        assert search_dirs(), "the plugin folder is remembered (the lookup of its options needs it)"
        assert closure_digest(run_roots(spec)) == before
    finally:  # leave no remembered folder to the tests after this one
        compose_config(["tracking=none"])


def test_the_versions_of_the_libraries_a_run_computes_with_are_read_without_importing_them():
    probe = ("import sys\nfrom mediated_transfer.provenance import library_versions\n"
             "v = library_versions()\nprint(v['numpy'], v['pymunk'], v['python'], 'torch' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.split()
    import numpy
    import pymunk

    assert out == [numpy.__version__, pymunk.version, platform.python_version(), "False"]
    assert set(library_versions()) == {"python", *LIBRARIES}


def test_a_digest_is_remembered_between_processes_while_its_files_are_unchanged(tmp_path, monkeypatch):
    """provenance/digest_cache.py: an entry is read back instead of walking the closure again,
    and any listed file with another modification time (or gone) makes it unusable."""
    import os

    from mediated_transfer import provenance
    from mediated_transfer.provenance import digest_cache

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    spec = RunSpec(representation="fsr", strategy="regular", n_source=15)
    digest = run_digest(spec)
    [entry] = (tmp_path / "mediated-transfer" / "digests").glob("*.json")
    files = json.loads(entry.read_text())["files"]
    loop = str(Path(provenance.__file__).parents[1] / "lockstep" / "run.py")
    assert loop in files  # the one run loop computes it

    def walked(*args):  # a remembered digest does not walk the closure
        raise AssertionError("closure walked")

    monkeypatch.setattr(provenance, "_digest", walked)
    assert run_digest(spec) == digest
    stat = os.stat(loop)
    try:
        os.utime(loop, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1))
        assert digest_cache.read(entry.stem) is None  # a file changed: computed again
    finally:
        os.utime(loop, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert digest_cache.read(entry.stem) == digest
    monkeypatch.setenv(digest_cache.SWITCH, "off")
    assert digest_cache.read(entry.stem) is None
