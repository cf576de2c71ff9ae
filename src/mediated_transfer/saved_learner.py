"""The trained learner a run leaves in its folder, and how to load it back to watch or evaluate.

At the end of a run (``save_learner: true``, the default) the learner is written next to
``result.json``:

- ``learner.npz`` (linear Q): the learner's ``state_dict()``, plain numpy arrays, read with
  ``np.load(allow_pickle=False)``;
- ``learner.pt`` (DQN): its ``state_dict()``, tensors and numbers, read with
  ``torch.load(weights_only=True)``. The replay buffer's transitions are left out (10 MB per run
  at paper scale, not needed to act): the reloaded DQN acts exactly as the trained one, but
  learning on from it would start with an empty buffer.
- ``learner.pt`` (SB3's PPO and DQN): the policy's tensors, in the same format. The reloaded
  model acts as the trained one; its optimizer and buffers are not saved (no learning on).

Neither format unpickles objects. Each file also holds ``meta``: a JSON text with the file
format and the run's ``RunSpec`` (the learner's configuration, the world, the seed), so a file
is enough to rebuild its learner; the run's ``result.json`` is not needed (it is written after
the learner, and when it is there its config is checked against the file's). Files are written
atomically. Run folders are outside git (``multirun/``, ``runs/``; .gitignore keeps only the
paper runs' result.json and curve.csv).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from .atomic import atomic_write
from .stored import DQN_FILE, LEARNER_FILES, LINEAR_FILE

if TYPE_CHECKING:
    from .learners.base import Learner
    from .runspec import RunSpec

FORMAT = 1
"""Version of the saved-learner files; a file of another version is refused."""


class SavedLearnerError(Exception):
    """A folder without a usable saved learner; the message is one line."""


def holds_tensors(state: dict) -> bool:
    """Whether a learner's state holds torch tensors (learner.pt) rather than numpy arrays
    (learner.npz): read from the state, so a plugin learner that extends the DQN is saved as
    the DQN is, whatever its algorithm's name."""
    return any(holds_tensors(v) if isinstance(v, dict) else type(v).__module__.split(".")[0] == "torch"
               for v in state.values())


def save_learner(learner: "Learner", spec: "RunSpec", folder: str | os.PathLike) -> Path:
    """Write ``learner`` (trained under ``spec``) to ``folder``; return the file's path."""
    meta = json.dumps({"format": FORMAT, "spec": asdict(spec)}, sort_keys=True)
    state = learner.state_dict()  # type: ignore[attr-defined]
    if holds_tensors(state):
        import torch

        path = Path(folder) / DQN_FILE
        if "buffer_transitions" in state:  # the DQN's replay buffer (and a subclass's)
            # clone(): a slice would still carry (and save) the whole storage.
            state["buffer_transitions"] = state["buffer_transitions"][:0].clone()
            state["buffer_size"] = state["buffer_position"] = 0
        state["meta"] = meta
        return atomic_write(path, lambda handle: torch.save(state, handle))
    return atomic_write(Path(folder) / LINEAR_FILE, lambda handle: np.savez(handle, meta=np.array(meta), **state))


def forget_learner(folder: str | os.PathLike) -> None:
    """Remove a saved learner from ``folder`` (a run about to be recomputed there must not
    leave an older run's learner next to its new result)."""
    for name in LEARNER_FILES:
        (Path(folder) / name).unlink(missing_ok=True)


def load_learner(folder: str | os.PathLike) -> tuple["Learner", "RunSpec"]:
    """The learner saved in ``folder`` and the RunSpec it was trained under.

    SavedLearnerError (one line) if the folder has none, or the file cannot be used.
    """
    from .learners.factory import make_learner
    from .config.spec import spec_from_dict

    folder = Path(folder)
    if not folder.is_dir():
        raise SavedLearnerError(f"{folder} is not a folder (give a run's folder, the one "
                                "holding result.json)")
    found = [folder / name for name in LEARNER_FILES if (folder / name).is_file()]
    if not found:
        if not (folder / "result.json").is_file():
            raise SavedLearnerError(f"{folder} is not a run's folder (no result.json, no "
                                    f"{' or '.join(LEARNER_FILES)})")
        raise SavedLearnerError(
            f"{folder} holds no saved learner ({' or '.join(LEARNER_FILES)}): the run finished before "
            "runs saved their learner, or ran with save_learner=false; run it again under "
            "another paths.root to get one (a finished run is skipped, not recomputed)"
        )
    if len(found) > 1:
        raise SavedLearnerError(f"{folder} holds both {LINEAR_FILE} and {DQN_FILE}; "
                                "remove the wrong one")
    path = found[0]
    try:
        state = _read(path)
        meta = json.loads(str(state.pop("meta")))
        if meta.get("format") != FORMAT:
            raise SavedLearnerError(f"{path} has format {meta.get('format')!r}; this code "
                                    f"reads format {FORMAT}")
        spec = spec_from_dict(meta["spec"])
        # Built by the targets the run recorded (a plugin's learner or representation is no
        # option of conf/); the generator state is restored from the file: the seed does not matter.
        with _quiet("hydra.utils"):  # it logs an import failure in 3 lines; the error below says it in one
            learner = make_learner(spec.algorithm, spec.representation, spec.algorithm_params,
                                   spec.representation_params, world=spec.make_world(), seed=0,
                                   algorithm_target=spec.algorithm_target,
                                   representation_target_path=spec.representation_target)
        learner.load_state_dict(state)  # type: ignore[attr-defined]
    except SavedLearnerError:
        raise
    except Exception as error:  # noqa: BLE001 - a damaged or foreign file: say so in one line
        hint = ("; the run's plugin must be importable: put its package on PYTHONPATH"
                if "not importable" in str(error) else "")
        raise SavedLearnerError(f"{path} cannot be loaded: {type(error).__name__}: "
                                f"{_first_line(error)}{hint}") from None
    _check_result(folder, spec, path)
    return learner, spec


def greedy_policy(folder: str | os.PathLike) -> tuple[Callable[[np.ndarray], int], "RunSpec"]:
    """The saved learner's greedy policy (observation -> action) and its RunSpec."""
    learner, spec = load_learner(folder)
    return (lambda observation: learner.act(observation, explore=False)), spec


def _read(path: Path) -> dict[str, Any]:
    if path.name == DQN_FILE:
        import torch

        return dict(torch.load(path, map_location="cpu", weights_only=True))
    with np.load(path, allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


def _check_result(folder: Path, spec: "RunSpec", path: Path) -> None:
    """The run's result.json, when there, must be of the learner's configuration."""
    from .config.spec import comparable, run_spec
    from .results import DamagedResult, RunResult

    if not RunResult.exists(folder):
        return
    try:
        config = RunResult.read(folder).config
    except DamagedResult as damaged:  # nothing to check the learner against: not used
        raise SavedLearnerError(f"{damaged}; rerun the run (its sweep sets the damaged files aside)") from None
    if not config:
        return
    try:
        recorded = comparable(run_spec(config))
    except Exception:  # noqa: BLE001 - a config this code no longer reads: nothing to compare
        return
    if recorded != comparable(spec):
        raise SavedLearnerError(f"{path} was trained under another configuration than "
                                f"{folder / 'result.json'}; rerun the run to save its learner")


@contextlib.contextmanager
def _quiet(logger: str):
    level = logging.getLogger(logger).level
    logging.getLogger(logger).setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logging.getLogger(logger).setLevel(level)


def _first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else ""
