"""README.md and docs/*.md refer only to things that exist.

For every page:
- every relative Markdown link or image names a file or folder of the repository, and an
  anchor into a Markdown page names one of its headings (GitHub's heading ids);
- every ``make <target>`` (in code blocks and inline code) names a rule of the Makefile, and a
  ``SCALE=`` given to make names a scale;
- every ``python -m mediated_transfer...`` names a module under src/ that ``-m`` can run;
- every Hydra override ``group=option`` (also ``+group=option``, comma sweeps, ``choice(...)``
  and the overrides inside ``ARGS="..."`` or ``--variant "..."``) whose group is a config group
  names one of the group's options, as Hydra itself lists them (conf/<group>/<option>.yaml, the
  dataclasses in Hydra's ConfigStore, Hydra's own launchers); ``n_source`` takes any k >= 0;
- every repository path in inline code (conf/, src/, tests/, scripts/, tuning/, docs/) exists,
  and every ``test_x.py::test_name`` names a test function of tests/test_x.py.

What cannot be checked reliably is left alone: placeholders (``<partition>``, ``...``,
``${...}``), dotted keys (``algorithm.lambda_=0.8``: the schema checks those when composing),
deletions (``~tuned``), and generated outputs (reports/, multirun/, runs/).
"""

from __future__ import annotations

import functools
import importlib
import os
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
CONF = ROOT / "conf"
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PAGE_IDS = [str(p.relative_to(ROOT)) for p in PAGES]

# Code blocks whose lines are all commands; in other non-Python blocks only "$ " lines are.
SHELL_LANGS = {"bash", "sh", "shell", "console", "zsh"}
# Inline-code paths under these folders must exist (the others are generated outputs).
CHECKED_DIRS = ("conf/", "src/", "tests/", "scripts/", "tuning/", "docs/")
PLACEHOLDER = re.compile(r"[<>*{}$|]|\.\.\.|…")
SWEEP_FUNCTIONS = ("range(", "interval(", "glob(", "tag(", "sort(", "shuffle(")


@dataclass(frozen=True)
class Snippet:
    """Text of a page that can hold commands: a code block's logical line or an inline span."""

    page: Path
    line: int
    text: str
    inline: bool

    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


@dataclass(frozen=True)
class Page:
    path: Path
    prose: str  # the page with its fenced code blocks blanked (line numbers kept)
    blocks: list[tuple[str, int, list[str]]]  # (language, first line number, lines)


@functools.cache
def parse(path: Path) -> Page:
    lines = path.read_text().split("\n")
    prose, blocks, fence = [], [], None
    for number, line in enumerate(lines, start=1):
        if fence is None and line.lstrip().startswith("```"):
            fence = (line.strip()[3:].strip().lower(), number + 1, [])
            prose.append("")
        elif fence is not None and line.strip().startswith("```"):
            blocks.append(fence)
            fence = None
            prose.append("")
        elif fence is not None:
            fence[2].append(line)
            prose.append("")
        else:
            prose.append(line)
    assert fence is None, f"{path.relative_to(ROOT)}: a code block is not closed"
    return Page(path, "\n".join(prose), blocks)


def line_of(text: str, offset: int) -> int:
    return text.count("\n", 0, offset) + 1


# Inline code: one or more backticks, the same number closes; it may wrap, not span paragraphs.
INLINE = re.compile(r"(`+)((?:(?!\1)[^\n]|\n(?!\s*\n))+?)\1")


def inline_spans(page: Page) -> list[tuple[int, int, str]]:
    """(start, end, code) of every inline code span of the page's prose."""
    return [(m.start(), m.end(), m.group(2).strip()) for m in INLINE.finditer(page.prose)]


def snippets(path: Path) -> list[Snippet]:
    page = parse(path)
    found = []
    for lang, first, lines in page.blocks:
        if lang in ("python", "py", "yaml", "text", "json", "csv"):
            continue
        logical, start = "", None
        for offset, line in enumerate(lines):
            if start is None:
                start = first + offset
            if line.rstrip().endswith("\\"):
                logical += line.rstrip()[:-1] + " "
                continue
            logical += line
            if lang in SHELL_LANGS:
                found.append(Snippet(path, start, logical.strip(), inline=False))
            elif logical.lstrip().startswith("$ "):
                found.append(Snippet(path, start, logical.lstrip()[2:], inline=False))
            logical, start = "", None
    for start, _, code in inline_spans(page):
        found.append(Snippet(path, line_of(page.prose, start), " ".join(code.split()), True))
    return found


def commands(snippet: Snippet) -> list[list[str]]:
    """The simple commands of a snippet, each as its words (comments and operators dropped)."""
    if snippet.text.startswith("$ "):
        text = snippet.text[2:]
    else:
        text = snippet.text
    text = re.sub(r"\d*[<>]&\d+", " ", text)  # 2>&1: no file
    text = re.sub(r"\d+(?=[<>])", " ", text)  # 2> file: the file is dropped below
    lexer = shlex.shlex(text, posix=True, punctuation_chars=";&|()<>")
    lexer.whitespace_split = True
    lexer.commenters = "" if snippet.inline else "#"
    try:
        words = list(lexer)
    except ValueError:  # unbalanced quotes: prose, not a command
        return []
    result, current, skip_next = [], [], False
    for word in words:
        if skip_next:
            skip_next = False
            continue
        if word and set(word) <= set(";&|()"):
            result.append(current)
            current = []
        elif word and set(word) <= set("<>"):
            skip_next = True  # a redirection's file
        else:
            current.append(word)
    result.append(current)
    return [c for c in result if c]


WRAPPERS = {"nohup", "time", "/usr/bin/time", "-v", "env", "sudo", "exec"}
ASSIGNMENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*=")


def strip_wrappers(words: list[str]) -> list[str]:
    i = 0
    while i < len(words) and (words[i] in WRAPPERS or ASSIGNMENT.match(words[i])):
        i += 1
    return words[i:]


def make_invocation(words: list[str]) -> tuple[list[str], dict[str, str]] | None:
    """(targets, variables) of a ``make`` command, or None if it is not one."""
    words = strip_wrappers(words)
    if not words or words[0] != "make":
        return None
    targets, variables = [], {}
    for word in words[1:]:
        word = word.strip("[]")  # [WORKERS=2]: an optional argument
        if not word or word.startswith("-"):
            continue
        if ASSIGNMENT.match(word):
            key, value = word.split("=", 1)
            variables[key] = value
        elif not PLACEHOLDER.search(word):
            targets.append(word)
    return targets, variables


PYTHON = re.compile(r"^(?:.*/)?python(?:3(?:\.\d+)?)?$")


def python_module(words: list[str]) -> tuple[str, list[str]] | None:
    """(module, its arguments) of a ``python -m mediated_transfer...`` command, or None."""
    for i, word in enumerate(words[:-2]):
        if PYTHON.match(word) and words[i + 1] == "-m":
            module = words[i + 2]
            if module == "mediated_transfer" or module.startswith("mediated_transfer."):
                return module, words[i + 3 :]
            return None
    return None


@functools.cache
def make_targets() -> frozenset[str]:
    rule = re.compile(r"^([A-Za-z0-9_.%/-][A-Za-z0-9_.%/ -]*?)\s*::?(?![=])")
    targets = set()
    for line in (ROOT / "Makefile").read_text().split("\n"):
        if line.startswith(("\t", "#", " ")):
            continue
        m = rule.match(line)
        if m and not m.group(1).startswith("."):
            targets.update(m.group(1).split())
    return frozenset(targets)


def module_problem(module: str) -> str | None:
    parts = module.split(".")
    if not all(re.fullmatch(r"[A-Za-z_]\w*", p) for p in parts):
        return f"'{module}' is not a module name"
    base = SRC.joinpath(*parts)
    if base.with_suffix(".py").is_file():
        return None
    if (base / "__init__.py").is_file():
        if (base / "__main__.py").is_file():
            return None
        return f"'python -m {module}': the package {base.relative_to(ROOT)} has no __main__.py"
    return f"'python -m {module}': no module src/{'/'.join(parts)}.py or package"


@functools.cache
def group_options(group: str) -> tuple[str, ...]:
    """The options Hydra offers for a config group (empty: not a group)."""
    # What `python -m mediated_transfer` imports registers the dataclass options.
    importlib.import_module("mediated_transfer.__main__")
    return tuple(_loader().get_group_options(group))


@functools.cache
def _loader():
    from hydra._internal.config_loader_impl import ConfigLoaderImpl
    from hydra._internal.utils import create_config_search_path

    return ConfigLoaderImpl(config_search_path=create_config_search_path(str(CONF)))


def numeric_group(group: str) -> bool:
    return group == "n_source"  # any k >= 0 (config/compose.py), beyond conf/n_source/*.yaml


def sweep_values(value: str) -> list[str] | None:
    """The options of a (sweep) value, or None when they cannot be listed reliably."""
    value = value.strip()
    if value.startswith(SWEEP_FUNCTIONS):
        return None
    if value.startswith("choice(") and value.endswith(")"):
        value = value[len("choice(") : -1]
    values = [v.strip().strip("'\"") for v in value.split(",")]
    if any(not v or PLACEHOLDER.search(v) for v in values):
        return None
    return values


PLUGIN_CONF = ROOT / "examples" / "plugins" / "my_plugins" / "conf"
"""The worked plugin examples' config folder (docs/extending.md): its options count where a
command puts it on the search path, and on the page that documents them."""


def searchpath_conf(words: list[str], plugins: bool) -> list[Path]:
    """The config folders a command puts on Hydra's search path (pkg:// or file://); the worked
    examples' folder where the page documents them or a command names a path of its own."""
    from mediated_transfer.config.compose import _source_dir

    folders = [PLUGIN_CONF] if plugins else []
    for word in words:
        if not word.startswith("hydra.searchpath="):
            continue
        for scheme, where in re.findall(r"(pkg|file)://([^,\]\s'\"]+)", word):
            if scheme == "file":
                folders.append(ROOT / where)
                continue
            # as the config loader finds it; the worked examples are a package the reader installs
            examples = [ROOT / "examples" / kind / where.replace(".", "/") for kind in ("plugins", "worlds")]
            folders.append(_source_dir("pkg", where) or next((f for f in examples if f.is_dir()), examples[0]))
    return folders


def override_problems(words: list[str], plugins: bool = False) -> list[str]:
    """Problems of the Hydra overrides among words (a word may hold several, space-separated)."""
    problems = []
    conf_folders = searchpath_conf(words, plugins)
    for word in words:
        for token in word.split():
            if token.startswith("~") or "=" not in token:
                continue
            key, value = token.split("=", 1)
            key = key.lstrip("+")
            if not key or "." in key or PLACEHOLDER.search(key):
                continue
            options = group_options(key)
            if not options:
                continue
            options = (*options, *(f.stem for c in conf_folders for f in (c / key).glob("*.yaml")))
            values = sweep_values(value)
            if values is None:
                continue
            for v in values:
                if v == "null" or v in options:
                    continue
                if numeric_group(key) and v.isdigit():
                    continue
                problems.append(
                    f"'{key}={v}': no option '{v}' in group '{key}' "
                    f"(conf/{key}/{v}.yaml or a registered config); options: {', '.join(options)}"
                )
    return problems


# ---------------------------------------------------------------------------------------------
# Links


LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def slug(heading: str) -> str:
    """GitHub's id of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`([^`]*)`", r"\1", heading.strip().lower())
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link's text only
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


@functools.cache
def anchors(path: Path) -> frozenset[str]:
    seen: dict[str, int] = {}
    result = set()
    for line in parse(path).prose.split("\n"):
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        base = slug(m.group(1))
        count = seen.get(base, 0)
        seen[base] = count + 1
        result.add(base if count == 0 else f"{base}-{count}")
    return frozenset(result)


def link_problems(path: Path) -> list[str]:
    page = parse(path)
    prose = page.prose
    for start, end, _ in inline_spans(page):  # links are not looked for inside inline code
        prose = prose[:start] + re.sub(r"[^\n]", " ", prose[start:end]) + prose[end:]
    problems = []
    for m in LINK.finditer(prose):
        target = m.group(1)
        where = f"{path.relative_to(ROOT)}:{line_of(prose, m.start())}"
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
            continue
        file_part, _, anchor = target.partition("#")
        # Lexically, as a browser resolves a link (a symlink is not followed out of the tree).
        resolved = Path(os.path.normpath(path.parent / file_part)) if file_part else path
        if not resolved.exists():
            problems.append(f"{where}: link target '{target}' does not exist ({file_part})")
            continue
        if ROOT not in resolved.parents and resolved != ROOT:
            problems.append(f"{where}: link target '{target}' lies outside the repository")
            continue
        if anchor and resolved.suffix == ".md" and anchor not in anchors(resolved):
            problems.append(
                f"{where}: link '{target}': no heading with id '#{anchor}' in "
                f"{resolved.relative_to(ROOT)} (ids: {', '.join(sorted(anchors(resolved)))})"
            )
    return problems


# ---------------------------------------------------------------------------------------------
# The tests


def test_there_are_pages_and_they_are_linked_from_the_readme():
    assert (ROOT / "docs" / "README.md").is_file()
    readme = parse(ROOT / "README.md").prose
    index = parse(ROOT / "docs" / "README.md").prose
    for page in PAGES[1:]:
        if page.name == "README.md":
            continue
        assert f"docs/{page.name}" in readme, f"README.md does not link docs/{page.name}"
        assert f"({page.name}" in index, f"docs/README.md does not link {page.name}"


@pytest.mark.parametrize("path", PAGES, ids=PAGE_IDS)
def test_relative_links_exist(path):
    problems = link_problems(path)
    assert not problems, "broken links:\n" + "\n".join(problems)


@pytest.mark.parametrize("path", PAGES, ids=PAGE_IDS)
def test_make_targets_exist(path):
    problems = []
    for snippet in snippets(path):
        for words in commands(snippet):
            invocation = make_invocation(words)
            if invocation is None:
                continue
            targets, variables = invocation
            for target in targets:
                if target not in make_targets():
                    problems.append(
                        f"{snippet.where()}: 'make {target}': no such target in the Makefile "
                        f"(targets: {', '.join(sorted(make_targets()))})"
                    )
            scale = variables.get("SCALE")
            if scale and not PLACEHOLDER.search(scale) and scale not in group_options("scale"):
                problems.append(f"{snippet.where()}: 'SCALE={scale}': no such scale")
            if "ARGS" in variables:
                problems += [f"{snippet.where()}: {p}" for p in override_problems([variables["ARGS"]])]
    assert not problems, "make commands that name nothing:\n" + "\n".join(dict.fromkeys(problems))


@pytest.mark.parametrize("path", PAGES, ids=PAGE_IDS)
def test_python_modules_exist(path):
    problems = []
    for snippet in snippets(path):
        for words in commands(snippet):
            found = python_module(words)
            if found and (problem := module_problem(found[0])):
                problems.append(f"{snippet.where()}: {problem}")
    assert not problems, "modules that do not exist:\n" + "\n".join(problems)


@pytest.mark.parametrize("path", PAGES, ids=PAGE_IDS)
def test_config_overrides_name_existing_options(path):
    problems = []
    for snippet in snippets(path):
        checked = False
        for words in commands(snippet):
            found = python_module(words)
            if found:
                checked = True
                problems += [f"{snippet.where()}: {p}" for p in override_problems(found[1])]
        if snippet.inline and not checked:
            # Inline code that only shows overrides: `env=tool_frame`, `tuned=provisional`.
            tokens = snippet.text.split()
            if tokens and all("=" in t and not t.startswith("-") for t in tokens):
                problems += [f"{snippet.where()}: {p}"
                             for p in override_problems(tokens, plugins=path.name == "extending.md")]
    assert not problems, "overrides that name no option:\n" + "\n".join(dict.fromkeys(problems))


TEST_REFERENCE = re.compile(r"\b(test_\w+\.py)(?:::(\w+))?")
REPO_PATH = re.compile(r"^(?:" + "|".join(re.escape(d) for d in CHECKED_DIRS) + r")[\w./=-]*$")


@pytest.mark.parametrize("path", PAGES, ids=PAGE_IDS)
def test_repository_paths_and_tests_exist(path):
    page = parse(path)
    problems = []
    for start, _, code in inline_spans(page):
        where = f"{path.relative_to(ROOT)}:{line_of(page.prose, start)}"
        for token in code.split():
            token = token.strip(",;:()")
            if REPO_PATH.match(token) and not PLACEHOLDER.search(token):
                if not (ROOT / token).exists():
                    problems.append(f"{where}: '{token}' does not exist")
        for m in TEST_REFERENCE.finditer(code):
            test_file = ROOT / "tests" / m.group(1)
            if not test_file.is_file():
                problems.append(f"{where}: 'tests/{m.group(1)}' does not exist")
            elif m.group(2) and not re.search(
                rf"^\s*(?:async\s+)?def {re.escape(m.group(2))}\(", test_file.read_text(), re.M
            ):
                problems.append(f"{where}: no test '{m.group(2)}' in tests/{m.group(1)}")
    assert not problems, "paths and tests that do not exist:\n" + "\n".join(problems)
