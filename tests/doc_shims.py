"""The commands a documented ```bash block calls, as tests/test_doc_commands.py runs them: this
file is the ``python`` first on the block's PATH (``make`` and ``pip`` beside it are small shell
and Python shims written by the test).

Every ``python`` command that is not ``-m mediated_transfer...`` runs as written. A package
command is sent to a fork server (``serve``, one per test session, started by the test): a
process that imported the package once and forks a child per command, which runs the command's
module as ``python -m`` would (its argv, folder, environment, PYTHONPATH and standard streams are
the command's), so each command costs its work, not another second of imports.

``DOC_MODE=smoke`` (the blocks whose point is that they run): a ``python -m mediated_transfer``
command runs at smoke scale: each ``scale=<x>`` becomes ``scale=smoke`` (a command without one
gets it), one seed per cell (``scale.seeds=1``), ``tracking=none``, and ``paths.root`` the test's
folder unless the command names its own; the reporting commands get the same scale and folder;
``evaluate --episodes N`` evaluates at most 5 episodes. Everything else runs as written.

``DOC_MODE=dry`` (paper scale, whole-table sweeps, SLURM, a GPU, or runs other tests run end to
end): a run command is checked as the entry point checks it before any work, without the work:
its overrides are parsed as Hydra parses them, and the config of every distinct job of it (of
every cell of a sweep) is composed and checked, its plugins built (``dry_run``); a reporting
command composes its config and reads an empty run folder, which it must report as having no
runs (``run the sweep first``); any other module of the package prints its ``--help``.

PYTHONPATH: a block's own (``export PYTHONPATH=examples/plugins``) comes first, then the
suite's, so the code under test is the worktree's.
"""

from __future__ import annotations

import atexit
import contextlib
import json
import logging
import os
import re
import runpy
import signal
import socket
import subprocess
import sys
import traceback

PACKAGE = "mediated_transfer"
RUN = PACKAGE
REPORTING = (f"{PACKAGE}.reporting", f"{PACKAGE}.reporting.compare")
NO_RUNS = "run the sweep first"
"""What a reporting command says of a run folder without runs (dry mode's expected outcome)."""
EPISODES = 5
"""The most episodes ``evaluate`` runs at smoke scale."""


def smoke(module: str, args: list[str], root: str) -> list[str]:
    args = [re.sub(r"^scale=\w+$", "scale=smoke", a) for a in args]
    if module == RUN or module in REPORTING:
        if not any(a.startswith("scale=") for a in args):
            args.append("scale=smoke")
        if not any(a.startswith("paths.root=") for a in args):
            args.append(f"paths.root={root}")
    if module == RUN:
        args += ["scale.seeds=1", "tracking=none"]
    if module == f"{PACKAGE}.evaluate" and "--episodes" in args:
        at = args.index("--episodes") + 1
        args[at] = str(min(int(args[at]), EPISODES))
    return args


def main() -> int:
    """The ``python`` shim: a package command goes to the fork server, anything else to Python."""
    paths = [p for p in (os.environ.get("PYTHONPATH"), os.environ["DOC_PYTHONPATH"]) if p]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(paths)}
    args = sys.argv[1:]
    if len(args) < 2 or args[0] != "-m" or not args[1].startswith(PACKAGE):
        return subprocess.call([os.environ["DOC_PYTHON"], *args], env=env)
    module, rest = args[1], args[2:]
    if os.environ["DOC_MODE"] == "smoke":
        rest = smoke(module, rest, os.environ["DOC_ROOT"])
    request = json.dumps({"module": module, "args": rest, "cwd": os.getcwd(), "env": env,
                          "mode": os.environ["DOC_MODE"]}).encode()
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as server:
        server.connect(os.environ["DOC_SERVER"])
        socket.send_fds(server, [b"!"], [0, 1, 2])
        server.sendall(request)
        server.shutdown(socket.SHUT_WR)
        answer = b"".join(iter(lambda: server.recv(4096), b""))
    return int(answer or b"1")


# ---------------------------------------------------------------- the fork server and its children

def serve(address: str) -> None:
    """Import the package once, then fork a child per command sent to ``address``."""
    import mediated_transfer.app  # noqa: F401 - what every command imports
    import mediated_transfer.reporting  # noqa: F401
    import mediated_transfer.sweep  # noqa: F401

    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(address)
    listener.listen(8)
    children: set[int] = set()

    def reap(*_):
        while children:
            pid, _status = os.waitpid(-1, os.WNOHANG)
            if not pid:
                return
            children.discard(pid)

    def stop(*_):
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        for pid in list(children):
            os.waitpid(pid, 0)  # so that the children's CPU time is the server's (time(1) counts it)
        os._exit(0)

    signal.signal(signal.SIGCHLD, reap)
    signal.signal(signal.SIGTERM, stop)
    print("ready", flush=True)
    listener.settimeout(900)  # a server whose test session was killed ends on its own
    while True:
        try:
            conn, _ = listener.accept()
        except TimeoutError:
            stop()
        _, fds, _, _ = socket.recv_fds(conn, 1, 3)
        request = json.loads(b"".join(iter(lambda: conn.recv(65536), b"")))
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:
            listener.close()
            status = _child(request, fds)
            try:
                conn.sendall(str(status).encode())
            finally:
                os._exit(0)
        children.add(pid)
        conn.close()
        for fd in fds:
            os.close(fd)


def _child(request: dict, fds: list[int]) -> int:
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    for target, fd in enumerate(fds):
        os.dup2(fd, target)
        os.close(fd)
    os.chdir(request["cwd"])
    os.environ.clear()
    os.environ.update(request["env"])
    own = [os.path.abspath(p) for p in request["env"].get("PYTHONPATH", "").split(os.pathsep) if p]
    sys.path[:0] = [os.getcwd(), *own]
    module, args = request["module"], request["args"]
    try:
        if request["mode"] == "dry" and module == RUN:
            dry_run(args)
        elif request["mode"] == "dry" and module not in REPORTING:  # e.g. a study's report: its options
            sys.argv = [module, "--help"]
            with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):
                runpy.run_module(module, run_name="__main__", alter_sys=True)
        elif request["mode"] == "dry":
            status = _dry_report(module, args)
            _exit()
            return status
        else:
            sys.argv = [module, *args]
            runpy.run_module(module, run_name="__main__", alter_sys=True)
        status = 0
    except SystemExit as stop:
        status = _status(stop)
    except BaseException:  # noqa: BLE001 - the command's traceback, as Python prints it
        traceback.print_exc()
        status = 1
    _exit()
    return status


def _status(stop: SystemExit) -> int:
    if stop.code is None or isinstance(stop.code, int):
        return stop.code or 0
    print(stop.code, file=sys.stderr)
    return 1


def _exit() -> None:
    atexit._run_exitfuncs()
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()


def _dry_report(module: str, args: list[str]) -> int:
    root = os.path.join(os.environ["DOC_ROOT"], "dry")
    sys.argv = [module, *[a for a in args if not a.startswith("paths.root=")], f"paths.root={root}"]
    try:
        runpy.run_module(module, run_name="__main__", alter_sys=True)
    except SystemExit as stop:
        if isinstance(stop.code, str) and NO_RUNS in stop.code:
            return 0
        return _status(stop)
    print(f"dry report: {module} found runs in the empty folder {root}", file=sys.stderr)
    return 1


def dry_run(args: list[str]) -> None:
    """Check ``python -m mediated_transfer <args>`` as the entry point does before any work
    (app.cli and sweep.preflight), without the work: Hydra's parse of the command, every distinct
    job's config composed and checked, its plugins built. SystemExit(one line) if it is refused."""
    from hydra._internal.utils import get_args_parser
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.types import RunMode

    from mediated_transfer.config.compose import ConfigError, compose_config, prepare_overrides
    from mediated_transfer.config.spec import run_spec
    from mediated_transfer.sweep import _is_hydra_override, _try_plugins, _without_seed, planned_jobs

    parsed = get_args_parser().parse_intermixed_args(args)
    if parsed.cfg or parsed.info or parsed.run or parsed.help:
        raise SystemExit(f"dry run: the documented command only prints something: {args}")
    try:
        overrides = prepare_overrides(parsed.overrides)
        lines = OverridesParser.create().parse_overrides(list(overrides))
        fixed = [o.input_line for o in lines if not o.is_sweep_override()]
        base = compose_config(fixed, hydra=True)
        if not parsed.multirun and base.hydra.mode != RunMode.MULTIRUN:
            if len(fixed) < len(overrides):
                raise ConfigError(f"{' '.join(o.input_line for o in lines if o.is_sweep_override())} "
                                  "sweeps over values: add -m (--multirun)")
            jobs = [fixed]
        else:
            jobs = planned_jobs(base, [o for o in overrides if not _is_hydra_override(o)])
        searchpath = [o for o in overrides if o.lstrip("+").startswith("hydra.searchpath")]
        for job in _sample(jobs, [o for o in lines if o.is_sweep_override()]):
            cfg = base if set(job) | set(searchpath) == set(fixed) else compose_config(list(job) + searchpath, hydra=True)
            _try_plugins(run_spec(cfg))
    except ConfigError as error:
        raise SystemExit(f"Invalid configuration: {error}") from None


def _sample(jobs: list[list[str]], swept: list) -> list[tuple[str, ...]]:
    """The jobs a dry run composes (each costs a Hydra composition, about half a second): the
    first, and for each value the command line sweeps over, the first job with it. The other
    cells of an experiment's own sweep are composed by tests/test_config.py; seeds do not
    change whether a config is valid."""
    keys = {o.get_key_element() for o in swept} - {"seed"}
    wanted = {o for job in jobs for o in job if o.split("=", 1)[0] in keys}
    chosen = [jobs[0]]
    for value in sorted(wanted):
        chosen.append(next(job for job in jobs if value in job))
    return list(dict.fromkeys(tuple(o for o in job if not o.startswith("seed=")) for job in chosen))


if __name__ == "__main__":
    if sys.argv[1:2] == ["serve"]:
        serve(sys.argv[2])
    else:
        sys.exit(main())
