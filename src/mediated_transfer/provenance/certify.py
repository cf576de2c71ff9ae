"""Carry results over a refactor: a step of translations.json that maps the code digests of an
earlier commit to today's, per run kind, once the refactor is shown to compute the same curves.

    python -m mediated_transfer.provenance.certify --from <commit> --why "<the evidence>"

It checks the earlier commit out (a temporary git worktree), computes there the digest of every
built-in run kind (algorithm/representation/strategy, single and lockstep; a commit before the
closure scheme gives its whole-file digests, both variants), computes today's, and appends the
mapping. The evidence is the caller's: bit-identical reruns of committed runs of each learner
and strategy (tests/test_reruns.py reruns some in every CI run). A step never makes a result
current whose code then differed from the translated commit's: it maps that commit's digests only.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from . import PACKAGE, SCHEME, TRANSLATIONS, _git, append_translation, run_digest

_DIGESTS_AT_COMMIT = r"""
import json, sys
kinds = json.loads(sys.argv[1])
out = {}
try:
    from mediated_transfer.provenance import run_digest
    from mediated_transfer.run import RunSpec
    for kind in kinds:
        a, r, s, *lock = kind.split("/")
        s, _, target = s.partition("=")  # a plugin's strategy: name=dotted.path
        spec = RunSpec(algorithm=a, representation=r, strategy=s, n_source=0 if s == "none" else 1,
                       strategy_target=target or None)
        out[kind] = [run_digest(spec, bool(lock))]
except ImportError:  # the whole-file scheme (2): one digest per algorithm, two variants
    from mediated_transfer.provenance import source_digest
    for kind in kinds:
        a, r, s, *lock = kind.split("/")
        out[kind] = sorted({source_digest(algorithm=a, lockstep=bool(lock), whole_files=w) for w in (False, True)})
print(json.dumps(out))
"""


def builtin_kinds() -> list[str]:
    """Every run kind of the built-in options: algorithm/representation/strategy[/lockstep]."""
    from ..config.targets import builtin_target
    from ..learners.factory import ALGORITHMS, learner_target
    from ..plugins import owner_class

    strategies = ("none", "regular", "scaffolded")
    kinds = []
    for algorithm in ALGORITHMS:
        cls = owner_class(learner_target(algorithm))
        own_loop = getattr(cls, "run_loop", None) is not None
        for representation in cls.representations:
            builtin_target("representation", representation)  # exists
            for strategy in strategies:
                kinds.append(f"{algorithm}/{representation}/{strategy}")
                if not own_loop:
                    kinds.append(f"{algorithm}/{representation}/{strategy}/lockstep")
    return kinds


def plugin_kinds(strategies: list[str]) -> list[str]:
    """Run kinds of plugin strategies (``name=dotted.path``) with every built-in learner of the
    project's loop, as single runs (the kind a plugin's sweep runs)."""
    from ..learners.factory import ALGORITHMS, learner_target
    from ..plugins import owner_class

    kinds = []
    for algorithm in ALGORITHMS:
        cls = owner_class(learner_target(algorithm))
        for representation in cls.representations:
            kinds += [f"{algorithm}/{representation}/{strategy}" for strategy in strategies]
    return kinds


def _key(kind: str) -> str:
    """translations.json's key of a kind: a plugin's strategy by its option name (run_kind)."""
    a, r, s, *lock = kind.split("/")
    return "/".join([a, r, s.partition("=")[0], *lock])


def digests_now(kinds: list[str]) -> dict[str, str]:
    from ..run import RunSpec

    out = {}
    for kind in kinds:
        a, r, s, *lock = kind.split("/")
        s, _, target = s.partition("=")
        out[kind] = run_digest(RunSpec(algorithm=a, representation=r, strategy=s, n_source=0 if s == "none" else 1,
                                       strategy_target=target or None), bool(lock))
    return out


def digests_at(commit: str, kinds: list[str]) -> dict[str, list[str]]:
    """Each kind's digest(s) as the code of ``commit`` computes them."""
    root = Path(_git("rev-parse", "--show-toplevel") or PACKAGE.parents[1])
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "tree"
        subprocess.run(["git", "-C", str(root), "worktree", "add", "--detach", "-q", str(tree), commit], check=True)
        try:
            out = subprocess.run([sys.executable, "-c", _DIGESTS_AT_COMMIT, json.dumps(kinds)],
                                 env={"PYTHONPATH": str(tree / "src"), "PATH": "/usr/bin:/bin"},
                                 capture_output=True, text=True, check=True, cwd=tree)
        finally:
            subprocess.run(["git", "-C", str(root), "worktree", "remove", "--force", str(tree)], check=False)
    return json.loads(out.stdout)


def certify(commit: str, why: str, plugins: list[str] = ()) -> dict:
    kinds = builtin_kinds() + plugin_kinds(list(plugins))
    before, now = digests_at(commit, kinds), digests_now(kinds)
    mapping = {_key(kind): {old: now[kind] for old in before[kind] if old != now[kind]} for kind in kinds}
    step = {"why": why, "from_commit": _git("rev-parse", commit), "to_commit": _git("rev-parse", "HEAD"),
            "to_scheme": SCHEME, "map": {k: v for k, v in mapping.items() if v}}
    append_translation(step)
    return step


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--from", dest="commit", required=True, help="the commit whose digests to carry over")
    parser.add_argument("--why", required=True, help="why that commit and today's code compute the same")
    parser.add_argument("--plugin", action="append", default=[], metavar="NAME=TARGET",
                        help="a plugin strategy's runs to carry over too (its option name and _target_)")
    args = parser.parse_args(argv)
    bad = [p for p in args.plugin if not re.fullmatch(r"\w+=[\w.]+", p)]
    if bad:
        parser.error(f"--plugin {bad[0]}: expected NAME=dotted.path.Target")
    step = certify(args.commit, args.why, args.plugin)
    print(f"{TRANSLATIONS}: step from {step['from_commit'][:10]}: {sum(map(len, step['map'].values()))} "
          f"digests of {len(step['map'])} run kinds carried over")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
