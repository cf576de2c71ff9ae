"""Provenance, proportionate: every run kind's code is the code its committed fingerprint was
taken at, a few kinds' standing short runs reproduce their fingerprints here, and the carry-over
writes a translation exactly when a moved kind's short run computes what it computed before.

The first test is what stops a change of executed code from landing without either carrying the
kind's results over or accepting that it computes something else (``make carry-over``)."""

from __future__ import annotations

import json

import pytest
from omegaconf import OmegaConf

import mediated_transfer.provenance as provenance
from mediated_transfer.provenance import RESULTS_FORMAT, staleness
from mediated_transfer.provenance import fingerprints as record
from mediated_transfer.provenance import standing
from mediated_transfer.provenance.carry_over import _versions, carry_over, main

from .optional import DEEP, deep_option, needs_deep

COMMAND = "make carry-over (python -m mediated_transfer.provenance.carry_over)"


def _watched() -> dict[str, standing.Kind]:
    # Without torch the code of a deep learner, and of the lockstep loop (its stacked networks),
    # is another, and so is its digest (test_provenance.py): those kinds are checked with it.
    kinds = standing.kinds()
    return {key: kind for key, kind in kinds.items()
            if DEEP or not (deep_option(kind.algorithm) or deep_option(kind.representation) or kind.lockstep)}


def test_every_run_kinds_code_is_the_code_its_fingerprint_was_taken_at():
    entries = record.load()
    moved = []
    for key, kind in _watched().items():
        if key not in entries:
            moved.append(f"{key}: a new run kind, no fingerprint yet")
        elif entries[key].digest != kind.digest():
            moved.append(f"{key}: code digest {kind.digest()}, its fingerprint was taken at {entries[key].digest}")
    assert not moved, (
        f"the code of {len(moved)} run kinds changed since their fingerprints were taken:\n  " + "\n  ".join(moved)
        + f"\nrun {COMMAND}: it reruns their standing short runs and carries their results over where they "
        "compute the same; a change of behaviour that is meant: ACCEPT=\"why\" (make) or --accept \"why\"")


@pytest.mark.parametrize("key", [
    "linear_q/fsr/regular",
    "linear_q/rbf/scaffolded/lockstep",
    pytest.param("dqn/network/regular", marks=needs_deep),
    pytest.param("sb3_ppo/network/regular", marks=[needs_deep, pytest.mark.slow]),
])
def test_a_standing_short_run_reproduces_its_committed_fingerprint(key):
    # One kind per loop: the project's (linear, DQN), a lockstep group, SB3's. Bit for bit only
    # where the fingerprint was taken: the same libraries, and for torch the same processor too
    # (it picks its kernels by it); elsewhere the digest check above is the guard.
    entry = record.load()[key]
    here, machine_parts = _versions(), 2
    deep = deep_option(standing.kinds()[key].algorithm)
    same = entry.versions == here if deep else (
        entry.versions.split(", ")[:-machine_parts] == here.split(", ")[:-machine_parts])
    if not same:
        pytest.skip(f"{key}: fingerprint taken with {entry.versions}; here {here}")
    found = standing.standing_fingerprint(standing.kinds()[key])
    assert found == entry.fingerprint, (
        f"{key}: fingerprint {found[:12]}, committed {entry.fingerprint[:12]} (taken with {entry.versions}; "
        f"now {provenance.library_versions()}): another library version or machine may explain it; "
        f"otherwise the code computes something else: {COMMAND} --retake --kind {key}")


def test_every_strategy_of_the_committed_plugin_has_a_standing_run():
    # A new strategy of auto_curricula gets its kinds watched only once it has standing parameters.
    import auto_curricula.conf
    from pathlib import Path

    folder = Path(auto_curricula.conf.__file__).parent / "strategy"
    options = {path.stem: OmegaConf.load(path)["_target_"] for path in folder.glob("*.yaml")}
    assert options == {name: target for name, (target, _) in standing.PLUGIN_STRATEGIES.items()}


# --- the carry-over, on a toy: one kind whose fingerprint was "taken" at a digest it no longer has

OLD_DIGEST, FINGERPRINT = "0123456789abcdef", "f" * 64
TOY = standing.Kind("linear_q", "fsr", "none")


@pytest.fixture
def toy(tmp_path, monkeypatch):
    """translations.json (today's) and fingerprints.json (the toy's) in ``tmp_path``."""
    translations = tmp_path / "translations.json"
    translations.write_text(provenance.TRANSLATIONS.read_text())
    monkeypatch.setattr(provenance, "TRANSLATIONS", translations)
    monkeypatch.setattr(record, "FINGERPRINTS", tmp_path / "fingerprints.json")
    monkeypatch.setattr(standing, "kinds", lambda: {TOY.key: TOY})
    provenance._translations.cache_clear()
    record.save({TOY.key: record.Entry(OLD_DIGEST, FINGERPRINT, "a" * 40, False, "toy")})
    yield translations, tmp_path / "fingerprints.json"
    provenance._translations.cache_clear()


def _short_run_gives(monkeypatch, fingerprint: str) -> None:
    monkeypatch.setattr(standing, "standing_fingerprint", lambda kind, cache_dir=None: fingerprint)


def _old_result_is_stale() -> str | None:
    return staleness({"digest": OLD_DIGEST, "commit": "a" * 40}, RESULTS_FORMAT, TOY.spec())


def test_a_moved_kind_whose_short_run_computes_the_same_is_carried_over(toy, monkeypatch):
    translations, fingerprints = toy
    _short_run_gives(monkeypatch, FINGERPRINT)
    steps = len(json.loads(translations.read_text())["steps"])
    assert _old_result_is_stale()
    said = []
    outcome = carry_over(say=said.append)
    assert outcome.carried == [TOY.key] and not outcome.refused
    step = json.loads(translations.read_text())["steps"][-1]
    assert len(json.loads(translations.read_text())["steps"]) == steps + 1
    assert step["map"] == {TOY.key: {OLD_DIGEST: TOY.digest()}} and step["from_commit"] == "a" * 40
    assert "reproduced bit for bit" in step["why"] and step["to_scheme"] == provenance.SCHEME
    assert _old_result_is_stale() is None  # a result of the old code reads current
    assert record.load(fingerprints)[TOY.key].digest == TOY.digest()
    assert any(f"{TOY.key}: same fingerprint" in line for line in said)  # progress, per kind
    # Once carried, nothing is left to run.
    assert carry_over(say=said.append).carried == [] and len(json.loads(translations.read_text())["steps"]) == steps + 1


def test_a_moved_kind_whose_short_run_computes_something_else_is_refused(toy, monkeypatch, capsys):
    translations, fingerprints = toy
    _short_run_gives(monkeypatch, "e" * 64)
    before = translations.read_bytes(), fingerprints.read_bytes()
    assert main([]) == 1
    refused = [line for line in capsys.readouterr().out.splitlines() if "computes something else" in line]
    assert len(refused) == 1 and refused[0].strip().startswith(f"{TOY.key}: ")
    assert (translations.read_bytes(), fingerprints.read_bytes()) == before  # nothing written
    assert _old_result_is_stale()


def test_an_accepted_change_records_the_new_fingerprint_and_old_results_stay_stale(toy, monkeypatch):
    translations, fingerprints = toy
    _short_run_gives(monkeypatch, "e" * 64)
    steps = translations.read_text()
    assert main(["--accept", "the toy learns otherwise now"]) == 0
    entry = record.load(fingerprints)[TOY.key]
    assert (entry.fingerprint, entry.digest, entry.why) == ("e" * 64, TOY.digest(), "the toy learns otherwise now")
    assert translations.read_text() == steps and _old_result_is_stale()


def test_a_kind_whose_short_run_fails_is_named_and_nothing_is_written(toy, monkeypatch):
    translations, fingerprints = toy

    def fails(kind, cache_dir=None):
        raise RuntimeError("a learner that cannot be built\nsecond line")

    monkeypatch.setattr(standing, "standing_fingerprint", fails)
    before = translations.read_bytes(), fingerprints.read_bytes()
    outcome = carry_over(accept="even when accepted", say=lambda line: None)
    assert outcome.refused == {TOY.key: f"{TOY.key}: its standing run failed (RuntimeError: a learner that cannot "
                                        "be built)"}
    assert (translations.read_bytes(), fingerprints.read_bytes()) == before
