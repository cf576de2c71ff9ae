"""The documentation's Python examples run as written (no undefined names, no outdated API).

The examples live in README.md and docs/*.md (the environment's in docs/environment.md, the
Gymnasium wrapper's in docs/transfer-and-metrics.md); every ```python block of those files runs.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from .optional import needs_deep

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = sorted((ROOT / "docs").glob("*.md"))
PAGES = [README, *DOCS]
# The pages that hold the examples once held by the README.
EXAMPLE_PAGES = [ROOT / "docs" / "environment.md", ROOT / "docs" / "transfer-and-metrics.md"]


def _blocks(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


BLOCKS = [(page, code) for page in PAGES for code in _blocks(page)]
# An example that trains with torch or Stable-Baselines3 needs the deep extra.
DEEP_CODE = re.compile(r"^(import torch|from stable_baselines3)", re.M)


def test_docs_have_python_examples():
    assert BLOCKS
    for page in EXAMPLE_PAGES:
        assert _blocks(page), f"{page.relative_to(ROOT)} lost its Python example"


@pytest.mark.parametrize(
    "page, code",
    [pytest.param(page, code, marks=needs_deep) if DEEP_CODE.search(code) else (page, code) for page, code in BLOCKS],
    ids=[f"{page.relative_to(ROOT)}:block{i}" for i, (page, _) in enumerate(BLOCKS)],
)
def test_docs_python_example_runs(page, code):
    exec(compile(code, str(page), "exec"), {"__name__": "readme_example"})
