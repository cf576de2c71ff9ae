"""The install: the Pythons the Makefile accepts are the ones the package declares, the
interpreter is checked before anything is created, and constraints.txt pins every dependency."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.specifiers import SpecifierSet

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def _supported() -> list[str]:
    return re.search(r"^SUPPORTED\s*:=\s*(.+)$", (ROOT / "Makefile").read_text(), re.M).group(1).split()


def test_the_makefile_accepts_exactly_the_declared_pythons():
    declared = [c.rsplit(" :: ", 1)[1] for c in PROJECT["classifiers"] if c.startswith("Programming Language :: Python :: 3.")]
    assert _supported() == declared
    requires = SpecifierSet(PROJECT["requires-python"])
    assert all(f"{v}.0" in requires for v in declared)
    assert not any(f"3.{minor}.0" in requires for minor in (10, 14))


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_another_python_stops_make_at_once_naming_the_supported_ones(tmp_path):
    missing = subprocess.run(["make", "-s", "-C", str(ROOT), "install", f"PYTHON={tmp_path / 'python3.10'}",
                              f"VENV={tmp_path / 'venv'}"], capture_output=True, text=True, timeout=60)
    assert missing.returncode != 0
    assert "needs Python 3.11, 3.12 or 3.13" in missing.stderr and "not an interpreter" in missing.stderr
    assert not (tmp_path / "venv").exists()  # nothing created, nothing downloaded
    this = subprocess.run(["make", "-s", "-C", str(ROOT), "check-python", f"PYTHON={sys.executable}"],
                          capture_output=True, text=True, timeout=60)
    assert this.returncode == 0, this.stderr


def test_constraints_pin_every_dependency_and_extra():
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            name, _, version = line.partition("==")
            pins[re.sub(r"[-_.]+", "-", name).lower()] = version
    wanted = PROJECT["dependencies"] + [r for extra in PROJECT["optional-dependencies"].values() for r in extra]
    for text in wanted:
        requirement = Requirement(text)
        name = re.sub(r"[-_.]+", "-", requirement.name).lower()
        assert name in pins, f"{name} is not in constraints.txt"
        assert requirement.specifier.contains(pins[name], prereleases=True), f"{name}=={pins[name]} is outside {text}"
