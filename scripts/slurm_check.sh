#!/usr/bin/env bash
# `make slurm-check` (opt-in, not CI): the hydra/launcher=slurm preset against a real SLURM.
# Brings up a single-node SLURM from Debian's packages (scripts/slurm_local.sh), submits a smoke
# Table II sweep through the preset into a temporary root, checks that every run's result and
# MLflow run are there, that resubmitting submits nothing, that a timeout_min above the
# partition's limit is refused in one line, and that a lockstep sweep sends each cell's seeds
# as one job; stops the daemons it started, whatever happens.
set -euo pipefail
cd "$(dirname "$0")/.."
python=${PYTHON:-.venv/bin/python}
# This checkout's code, in the launcher and (inherited through sbatch) in the jobs.
export PYTHONPATH="$PWD/src${PYTHONPATH:+:$PYTHONPATH}"
work=$(mktemp -d /tmp/slurm-check.XXXXXX)
trap 'scripts/slurm_local.sh stop "$work/slurm"; echo "slurm-check: daemons stopped; files in $work"' EXIT

eval "$(scripts/slurm_local.sh start "$work/slurm" | tail -1)"
sinfo
root=$work/root
sweep=$root/multirun/table2_rbf/smoke
seeds=2
runs=$((11 * seeds))
args=(experiment=table2_rbf scale=smoke scale.seeds=$seeds "paths.root=$root"
      hydra/launcher=slurm hydra.launcher.runs_per_job=4 hydra.launcher.progress_every_s=5)

echo "== 1. submit a smoke Table II sweep ($runs runs) through the preset"
"$python" -m mediated_transfer "${args[@]}"

echo "== 2. every run has its result and its MLflow run"
"$python" - "$root" "$runs" <<'PY'
import sys
from pathlib import Path
from mediated_transfer.sweep import tracking

root, runs = Path(sys.argv[1]), int(sys.argv[2])
results = sorted((root / "multirun/table2_rbf/smoke").glob("*/seed=*/result.json"))
settings = tracking.TrackingSettings(f"sqlite:///{root / 'mlflow.db'}")
logged = tracking.find_runs(settings, "table2_rbf")
print(f"results: {len(results)}/{runs}, MLflow runs: {len(logged)}/{runs}")
assert len(results) == runs and len(logged) == runs, "missing results or MLflow runs"
PY

echo "== 3. resubmitting the finished sweep submits nothing"
before=$(ls "$sweep/.submitit" | wc -l)
"$python" -m mediated_transfer "${args[@]}" 2>&1 | tee "$work/resubmit.log"
after=$(ls "$sweep/.submitit" | wc -l)
grep -q "0 submitted in 0 jobs" "$work/resubmit.log"
[[ $before == "$after" ]] || { echo "slurm-check: the resubmission created $((after - before)) jobs" >&2; exit 1; }
echo "jobs in .submitit: $before before, $after after"

echo "== 4. timeout_min above the partition's limit: refused in one line"
set +e
"$python" -m mediated_transfer "${args[@]}" hydra.launcher.timeout_min=100000 >"$work/limit.out" 2>"$work/limit.err"
code=$?
set -e
cat "$work/limit.err"
[[ $code != 0 && $(grep -c . "$work/limit.err") == 1 ]] && grep -q "timeout_min=100000 is above partition" "$work/limit.err"

echo "== 5. lockstep: a cell's seeds in one job, trained together, each its own result"
lock_args=(experiment=table4_dnn scale=smoke scale.seeds=2 cell=none_0,regular_1 lockstep.runs=2 "paths.root=$root"
           hydra/launcher=slurm hydra.launcher.progress_every_s=5)
"$python" -m mediated_transfer "${lock_args[@]}" 2>&1 | tee "$work/lockstep.log"
grep -q "4 submitted in 2 jobs (2 runs per job)" "$work/lockstep.log"
"$python" - "$root" <<'PY'
import sys
from pathlib import Path
from mediated_transfer.results import RunResult

sweep = Path(sys.argv[1]) / "multirun/table4_dnn/smoke"
records = [RunResult.read(f.parent).code for f in sorted(sweep.glob("*/seed=*/result.json"))]
print(f"lockstep results: {len(records)}/4, group sizes {[r.get('lockstep_runs') for r in records]}")
assert len(records) == 4 and all(r.get("lockstep_runs") == 2 for r in records), records
PY

echo "slurm-check: OK"
