"""A stored run is validated when read: a damaged one (truncated, empty, random bytes, the wrong
JSON, a missing or unknown key, a value of the wrong kind, result.json replaced by a folder,
curve.csv cut short, garbage or deleted, a plausible edit) is named in one line, left out of
the report, which says so, and set aside (renamed, never deleted) and recomputed by the sweep.
Infinities that mean something round-trip through result.json; the others are refused.

Fault injection on a smoke-scale sweep made once per session and copied per test.
"""

from __future__ import annotations

import dataclasses
import json
import random
import shutil
from pathlib import Path

import pytest

from mediated_transfer.config.compose import ConfigError, compose_config
from mediated_transfer.config.spec import run_spec
from mediated_transfer.provenance.judge import check_same_run
from mediated_transfer.reporting.__main__ import main as reporting_main
from mediated_transfer.results import CURVE_FILE, RESULT_FILE, DamagedResult, RunResult
from mediated_transfer.slurm.jobs import is_finished
from mediated_transfer.stored import check, codec, seal
from mediated_transfer.stored.aside import SUFFIX, set_aside

from .optional import needs_deep
from .test_sweep import _run_cli

MULTIRUN = Path(__file__).resolve().parents[1] / "multirun"
SWEEP = "multirun/table2_rbf/smoke"
RUN = f"{SWEEP}/none_0/seed=1"


def _args(root: Path, cache: Path) -> list[str]:
    return ["experiment=table2_rbf", "cell=none_0,regular_1", "scale=smoke", "tracking=none",
            f"paths.root={root}", f"paths.cache_dir={cache}"]


@pytest.fixture(scope="session")
def pristine(tmp_path_factory) -> tuple[Path, Path]:
    """(root, cache) of a finished smoke sweep: two cells, two seeds each."""
    root, cache = tmp_path_factory.mktemp("pristine"), tmp_path_factory.mktemp("cache")
    _run_cli(*_args(root, cache), "hydra/launcher=basic")
    return root, cache


@pytest.fixture
def sweep(pristine, tmp_path) -> tuple[Path, Path]:
    root, cache = pristine
    copy = tmp_path / "root"
    shutil.copytree(root, copy)
    return copy, cache


def _edit(change):
    def inject(path: Path) -> None:
        record = json.loads(path.read_text())
        change(record)
        path.write_text(json.dumps(record, indent=2))
    return inject


def _curve(change):
    def inject(path: Path) -> None:
        curve = path.parent / CURVE_FILE
        curve.write_text(change(curve.read_text()))
    return inject


def _as_folder(path: Path) -> None:
    path.unlink()
    path.mkdir()
    (path / "note.txt").write_text("not a record")


def _plausible_edit_everywhere(path: Path) -> None:
    """<R> raised in result.json and curve.csv alike, its reward loss to match: consistent."""
    record = json.loads(path.read_text())
    record["mean_reward"] = [3.5, 3.75]
    record["reward_loss"] = 12.75
    path.write_text(json.dumps(record, indent=2))
    lines = (path.parent / CURVE_FILE).read_text().splitlines()
    rows = [line.split(",") for line in lines[1:]]
    rows[0][1], rows[1][1] = "3.5", "3.75"
    (path.parent / CURVE_FILE).write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")


def _edit_without_checksum(path: Path) -> None:
    """The consistent edit above, and the checksum that would show it deleted."""
    _plausible_edit_everywhere(path)
    _edit(lambda r: r.pop(codec.CHECKSUM))(path)


# fault -> (inject into result.json's path, what the one-line message says, the file it names)
FAULTS = {
    "truncated": (lambda p: p.write_text(p.read_text()[: len(p.read_text()) // 2]),
                  "is not valid JSON, cut short", RESULT_FILE),
    "empty": (lambda p: p.write_text(""), "is empty", RESULT_FILE),
    "random bytes": (lambda p: p.write_bytes(random.Random(0).randbytes(300)), "is not UTF-8 text", RESULT_FILE),
    "{}": (lambda p: p.write_text("{}"), "lacks the key(s) algorithm, budget", RESULT_FILE),
    "[]": (lambda p: p.write_text("[]"), "holds a JSON array, not a run's record", RESULT_FILE),
    "missing key": (_edit(lambda r: r.pop("mean_reward")), "lacks the key(s) mean_reward", RESULT_FILE),
    "unknown key": (_edit(lambda r: r.update(colour="blue")), "has unknown key(s) 'colour'", RESULT_FILE),
    "reward_loss text": (_edit(lambda r: r.update(reward_loss="abc")),
                         "reward_loss must be a finite number or null, got 'abc'", RESULT_FILE),
    "mean_reward nulls": (_edit(lambda r: r.update(mean_reward=[None, None])),
                          "mean_reward must be a list of finite numbers, got [None, None]", RESULT_FILE),
    "mean_reward text": (_edit(lambda r: r.update(mean_reward=["a", "b"])),
                         "mean_reward must be a list of finite numbers", RESULT_FILE),
    "result.json a folder": (_as_folder, "is a folder, not a run's record", RESULT_FILE),
    "curve truncated": (_curve(lambda t: t[: len(t) - 8]), "curve.csv", CURVE_FILE),
    "curve garbage": (_curve(lambda t: "\x00\x01garbage,,\nzz\n"), "does not start with its header", CURVE_FILE),
    "curve rows garbage": (_curve(lambda t: t.splitlines()[0] + "\n100,abc,0.0\n200,0.0,0.0\n"),
                           "line 2 is not step,mean_reward,success_rate", CURVE_FILE),
    "curve deleted": (lambda p: (p.parent / CURVE_FILE).unlink(), "is missing", CURVE_FILE),
    "plausible edit": (_edit(lambda r: r.update(mean_reward=[3.5, 3.75])),
                       "reward_loss 20.0 is not that of its mean_reward (12.75)", RESULT_FILE),
    "plausible edit everywhere": (_plausible_edit_everywhere,
                                  "differs from the checksum recorded when the run was written", RESULT_FILE),
    "plausible edit everywhere, checksum deleted": (_edit_without_checksum, "has no checksum", RESULT_FILE),
}


@pytest.mark.slow
@pytest.mark.parametrize("fault", FAULTS)
def test_reading_a_damaged_run_names_its_file_and_what_is_wrong(sweep, fault):
    root, _ = sweep
    inject, says, named = FAULTS[fault]
    folder = root / RUN
    inject(folder / RESULT_FILE)
    with pytest.raises(DamagedResult) as caught:
        RunResult.read(folder)
    message = str(caught.value)
    assert "\n" not in message and says in message
    assert message.startswith(f"{folder / named}: ")
    assert not is_finished(folder, rerun_stale=False)  # the launchers submit it again


def test_a_curve_edited_alone_is_named_against_result_json(sweep):
    root, _ = sweep
    curve = root / RUN / CURVE_FILE
    lines = curve.read_text().splitlines()
    curve.write_text("\n".join([lines[0], lines[1].replace(",0.0,", ",9.5,", 1), *lines[2:]]) + "\n")
    with pytest.raises(DamagedResult, match=r"curve.csv: step,mean_reward,success_rate 100,9.5,0.0, but "
                                            r"result.json has 100,0.0,0.0"):
        RunResult.read(root / RUN)


@pytest.mark.slow
def test_the_report_leaves_damaged_runs_out_and_names_each(sweep, capsys):
    root, cache = sweep
    FAULTS["truncated"][0](root / RUN / RESULT_FILE)
    FAULTS["curve deleted"][0](root / SWEEP / "regular_1" / "seed=0" / RESULT_FILE)
    args = [a for a in _args(root, cache) if not a.startswith("cell=")]
    assert reporting_main(args) == 0  # never a traceback: the valid runs make the table
    out, err = capsys.readouterr()
    assert "table2_rbf: 2 runs (2 damaged left out) -> " in out
    left_out = [line for line in err.splitlines() if "left out: " in line]
    assert len(left_out) == 2
    assert any(f"{root / RUN / RESULT_FILE}: is not valid JSON" in line for line in left_out)
    assert any(f"{root / SWEEP / 'regular_1' / 'seed=0' / CURVE_FILE}: is missing" in line for line in left_out)
    table = (root / "reports" / "smoke" / "table2_rbf.md").read_text()
    assert "| without transfer | 0 | 1/2 |" in table and "2 damaged runs were left out" in table


@pytest.mark.slow
@pytest.mark.parametrize("fault", ["truncated", "result.json a folder", "curve deleted", "plausible edit everywhere"])
def test_the_sweep_sets_a_damaged_run_aside_and_computes_it_again(sweep, fault):
    root, cache = sweep
    folder = root / RUN
    pristine = (folder / RESULT_FILE).read_text()
    other = root / SWEEP / "none_0" / "seed=0" / RESULT_FILE
    untouched = other.stat().st_mtime_ns
    FAULTS[fault][0](folder / RESULT_FILE)
    damaged = {p.name: (p.read_bytes() if p.is_file() else None) for p in folder.iterdir()
               if p.name in (RESULT_FILE, CURVE_FILE)}

    _run_cli(*_args(root, cache), "hydra/launcher=basic")  # no traceback, no refusal

    aside = {p.name.split(SUFFIX)[0]: p for p in folder.iterdir() if SUFFIX in p.name}
    assert set(damaged) <= set(aside)  # every damaged file kept, renamed, none deleted
    for name, content in damaged.items():
        assert aside[name].is_dir() if content is None else aside[name].read_bytes() == content
    again = RunResult.read(folder)  # recomputed: valid, and the same run as before the damage
    assert again.mean_reward == json.loads(pristine)["mean_reward"]
    assert other.stat().st_mtime_ns == untouched  # the sound runs were reused
    log = (folder / "mediated_transfer.log").read_text()
    [line] = [line for line in log.splitlines() if "set aside as" in line]
    assert str(folder) in line and "computing the run again" in line


def test_set_aside_renames_the_runs_files_only_and_never_overwrites(tmp_path):
    folder = tmp_path / "seed=0"
    (folder / "algorithm.lambda_=0.5").mkdir(parents=True)  # a variant's run lives inside
    for name in (RESULT_FILE, CURVE_FILE, "learner.npz", "mediated_transfer.log"):
        (folder / name).write_text(name)
    first = set_aside(folder)
    (folder / RESULT_FILE).write_text("again")
    second = set_aside(folder)
    assert [p.name.split(SUFFIX)[0] for p in first] == [RESULT_FILE, CURVE_FILE, "learner.npz"]
    assert [p.name for p in second] == [first[0].name + "-2"]
    assert {p.read_text() for p in (*first, *second)} == {RESULT_FILE, CURVE_FILE, "learner.npz", "again"}
    assert (folder / "algorithm.lambda_=0.5").is_dir() and (folder / "mediated_transfer.log").is_file()


def test_every_committed_run_carries_a_checksum_and_reads_valid():
    # Those written before checksums existed were sealed once (stored/seal.py).
    folders = [p.parent for p in MULTIRUN.glob(f"**/{RESULT_FILE}")]
    assert len(folders) >= 2700
    for folder in folders:
        assert codec.CHECKSUM in json.loads((folder / RESULT_FILE).read_text()), folder
        RunResult.read(folder)


def test_sealing_adds_the_checksum_and_nothing_else(sweep):
    root, _ = sweep
    path = root / RUN / RESULT_FILE
    sealed_text = path.read_text()
    _edit(lambda r: r.pop(codec.CHECKSUM))(path)  # as written before issue 38
    with pytest.raises(DamagedResult, match="has no checksum.*seal"):
        RunResult.read(root / RUN)
    assert seal.seal(root / RUN) and not seal.seal(root / RUN)  # once
    assert path.read_text() == sealed_text
    RunResult.read(root / RUN)


def test_sealing_leaves_a_damaged_record_as_it_is_and_names_it(sweep, capsys):
    root, _ = sweep
    path = root / RUN / RESULT_FILE
    _edit(lambda r: (r.pop(codec.CHECKSUM), r.update(mean_reward=[3.5, 3.75])))(path)
    damaged = path.read_text()
    assert seal.main([str(root)]) == 1
    out, err = capsys.readouterr()
    assert "sealed 0 record(s); 3 already had a checksum; 1 damaged" in out
    assert f"not sealed: {path}: reward_loss 20.0 is not that of its mean_reward" in err
    assert path.read_text() == damaged


def test_a_new_result_records_its_checksum_and_reads_back_equal(sweep):
    root, _ = sweep
    text = (root / RUN / RESULT_FILE).read_text()
    record = json.loads(text)
    assert record[codec.CHECKSUM] == codec.checksum(record)
    result = RunResult.read(root / RUN)
    result.write(root / "copy")
    assert (root / "copy" / RESULT_FILE).read_text() == text


def test_the_checked_keys_are_run_results_fields():
    fields = {f.name: f for f in dataclasses.fields(RunResult)}
    assert set(check.FIELDS) == set(fields)
    defaults = {n for n, f in fields.items()
                if f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING}
    assert check.OPTIONAL == defaults


# --- non-finite values: refused, or kept through result.json -----------------------------------

@pytest.mark.parametrize("override", ["algorithm.adam_epsilon=inf", "algorithm.huber_delta=-inf",
                                      "algorithm.lr=inf", "algorithm.huber_delta=nan"])
def test_a_non_finite_value_is_refused_in_one_line_naming_the_key(override):
    key = override.split("=")[0]
    with pytest.raises(ConfigError) as caught:
        run_spec(compose_config(["algorithm=dqn", "representation=network", "scale=smoke", override]))
    assert "\n" not in str(caught.value) and key.split(".")[1] in str(caught.value)


def test_an_infinity_in_the_config_is_written_as_inf_and_read_back_as_infinity(sweep):
    root, _ = sweep
    result = RunResult.read(root / RUN)
    result.config["algorithm"]["huber_delta"] = float("inf")
    result.learner_stats["last_loss"] = float("nan")
    result.write(root / "inf")
    text = (root / "inf" / RESULT_FILE).read_text()
    strict = json.loads(text, parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))
    assert strict["config"]["algorithm"]["huber_delta"] == "inf" and strict["learner_stats"]["last_loss"] is None
    assert RunResult.read(root / "inf").config["algorithm"]["huber_delta"] == float("inf")


@needs_deep
@pytest.mark.slow
@pytest.mark.parametrize("key", ["algorithm.huber_delta", "algorithm.max_grad_norm"])
def test_an_infinity_that_means_something_runs_and_the_same_command_resumes(tmp_path, key, capsys):
    args = ["algorithm=dqn", "representation=network", "scale=smoke", "tracking=none", f"paths.root={tmp_path}",
            f"{key}=inf"]
    _run_cli(*args)
    [stored] = tmp_path.rglob(RESULT_FILE)
    assert RunResult.read(stored.parent).config["algorithm"][key.split(".")[1]] == float("inf")
    first = stored.stat().st_mtime_ns
    _run_cli(*args)  # resumes: found, neither refused nor recomputed
    assert stored.stat().st_mtime_ns == first and "found, skipped" in capsys.readouterr().out


@needs_deep
@pytest.mark.slow
def test_a_result_that_earlier_code_wrote_with_null_for_inf_is_set_aside_and_recomputed(tmp_path):
    args = ["algorithm=dqn", "representation=network", "scale=smoke", "tracking=none", f"paths.root={tmp_path}",
            "algorithm.huber_delta=inf"]
    _run_cli(*args)
    [stored] = tmp_path.rglob(RESULT_FILE)
    record = json.loads(stored.read_text())
    record["config"]["algorithm"]["huber_delta"] = None  # as the code before issue 38 wrote it
    record[codec.CHECKSUM] = codec.checksum(record)  # sealed as the committed runs are
    stored.write_text(json.dumps(record))
    with pytest.raises(DamagedResult, match="its recorded config is not a run this code can read"):
        check_same_run(RunResult.read(stored.parent), run_spec(compose_config(args)), stored.parent)
    _run_cli(*args)
    assert RunResult.read(stored.parent).config["algorithm"]["huber_delta"] == float("inf")
    assert [p.name.split(SUFFIX)[0] for p in stored.parent.glob(f"*{SUFFIX}*")].count(RESULT_FILE) == 1
