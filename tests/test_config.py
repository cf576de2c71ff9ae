"""conf/: every group option composes into a runnable config, each experiment's sweep covers
exactly its table's rows, any N_source works, and bad overrides fail at once with a one-line
message naming the key and the allowed values."""

from __future__ import annotations

import dataclasses
import re

import pytest
from hydra import compose, initialize_config_dir
from hydra.utils import get_class
from omegaconf import OmegaConf

from mediated_transfer.config import schema
from mediated_transfer.config.compose import CONF_DIR, ConfigError, compose_config, prepare_overrides
from mediated_transfer.config.spec import run_spec
from mediated_transfer.reporting.paper import paper_rows
from mediated_transfer.sweep import planned_jobs
# What an option needs beside it to form a valid run (the rest stays at the defaults).
COMPANIONS = {
    "algorithm=dqn": ["representation=network"],
    "representation=network": ["algorithm=dqn"],
    "strategy=regular": ["n_source=15"],
    "strategy=scaffolded": ["n_source=15"],
    "tracking=server": ["tracking.uri=http://127.0.0.1:5000"],
}
PAPER_TABLE = {"table2_rbf": "II", "table3_fsr": "III", "table4_dnn": "IV"}
LEARNER = {"table2_rbf": ("linear_q", "rbf"), "table3_fsr": ("linear_q", "fsr"), "table4_dnn": ("dqn", "network")}


@pytest.fixture(scope="module")
def hydra_context():
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        yield


def _compose(*overrides: str, hydra: bool = False):
    return compose("config", overrides=prepare_overrides(overrides), return_hydra_config=hydra)


# Not groups of a run: Hydra's own, whole experiments, and the tuning's search spaces (read by
# mediated_transfer.tuning, checked in tests/test_tuning.py).
NOT_RUN_GROUPS = ("hydra", "experiment", "hparams_search")


def _options() -> list[str]:
    out = []
    for group in sorted(p for p in CONF_DIR.iterdir() if p.is_dir() and p.name not in NOT_RUN_GROUPS):
        out += [f"{group.name}={option.stem}" for option in sorted(group.glob("*.yaml"))]
    for group, options in schema.PYTHON_OPTIONS.items():
        out += [f"{group}={name}" for name in options]
    return sorted(out)


def _companions(option: str) -> list[str]:
    group, name = option.split("=")
    if group == "n_source" and name != "0":
        return ["strategy=regular"]
    if group == "tuned" and name != "provisional":  # tuned values compose with their own learner
        algorithm, representation = _learner_of(name)
        return [f"algorithm={algorithm}", f"representation={representation}"]
    return COMPANIONS.get(option, [])


@pytest.mark.parametrize("option", _options())
def test_every_group_option_composes_into_a_valid_run(hydra_context, option):
    cfg = _compose(option, *_companions(option))
    OmegaConf.to_container(cfg, resolve=True)  # every interpolation resolves
    spec = run_spec(cfg)
    group, name = option.split("=")
    if group in ("algorithm", "representation"):
        assert getattr(spec, group) == name
    if group == "cell":  # custom: the strategy and N_source the command gives
        assert f"{spec.strategy}_{spec.n_source}" == cfg.cell == (name if name != "custom" else "none_0")
    if group == "n_source":
        assert spec.n_source == int(name)


@pytest.mark.parametrize("option", [o for o in _options() if o.split("=")[0] in ("algorithm", "representation")])
def test_every_learner_option_instantiates(hydra_context, option):
    from mediated_transfer.learners.factory import make_learner

    spec = run_spec(_compose(option, *_companions(option)))
    learner = make_learner(spec.algorithm, spec.representation, spec.algorithm_params,
                           spec.representation_params, world=spec.world, seed=0)
    assert learner.act(_observation(), explore=False) in range(11)


def _observation():
    import numpy as np

    obs = np.zeros(11)
    obs[:6] = 5.0
    obs[10] = 1.0  # active picking location O
    return obs


@pytest.mark.parametrize("option", ["tracking=sqlite", "tracking=server", "tracking=none"])
def test_tracking_options_give_settings_or_disable_tracking(hydra_context, option, tmp_path):
    from mediated_transfer.sweep.tracking import TrackingSettings

    cfg = _compose(option, *_companions(option), f"paths.root={tmp_path}")
    if cfg.tracking.enabled:
        settings = TrackingSettings.from_config(cfg.tracking)
        assert settings.uri.startswith(("sqlite:///", "http://"))
    else:
        assert option == "tracking=none"


@pytest.mark.parametrize("launcher, target", [
    ("parallel", "hydra_plugins.mediated_transfer_launcher.local_launcher.MediatedJoblibLauncher"),
    ("submitit_local", "hydra_plugins.hydra_submitit_launcher.submitit_launcher.LocalLauncher"),
    ("slurm", "hydra_plugins.mediated_transfer_launcher.slurm_launcher.MediatedSlurmLauncher"),
    ("basic", "hydra._internal.core_plugins.basic_launcher.BasicLauncher"),
])
def test_launcher_presets_compose_and_name_an_importable_launcher(hydra_context, launcher, target):
    cfg = _compose(f"hydra/launcher={launcher}", hydra=True)
    assert cfg.hydra.launcher._target_ == target
    get_class(target)


def test_default_launcher_is_joblib_with_one_worker_per_core(hydra_context):
    from hydra_plugins.hydra_joblib_launcher.joblib_launcher import JoblibLauncher

    launcher = _compose(hydra=True).hydra.launcher
    assert issubclass(get_class(launcher._target_), JoblibLauncher) and launcher.n_jobs == -1
    # Without lockstep groups (the CPU default), one job per run, as Hydra's joblib launcher.
    cfg = _compose(hydra=True)
    assert cfg.lockstep.runs is None and cfg.lockstep.device == "cpu"


@pytest.mark.parametrize("experiment", sorted(PAPER_TABLE))
def test_experiment_sweep_covers_exactly_the_papers_rows_times_seeds(hydra_context, experiment):
    cfg = _compose(f"experiment={experiment}", "scale=quick", hydra=True)
    assert cfg.hydra.mode.name == "MULTIRUN" and cfg.name == experiment
    jobs = planned_jobs(cfg)
    seeds = list(range(int(cfg.scale.seeds)))
    # Each cell option sets exactly the strategy and N_source its name says (checked above by
    # test_every_group_option_composes_into_a_valid_run), so naming the paper's cells suffices.
    cells = sorted({_cell(job) for job in jobs})
    assert cells == sorted(p.cell for p in paper_rows(PAPER_TABLE[experiment]))
    assert len(jobs) == len(cells) * len(seeds) == len({tuple(sorted(j)) for j in jobs})
    for cell in cells:
        assert sorted(_seed(j) for j in jobs if _cell(j) == cell) == seeds
    # Seed by seed, each seed over the paper's rows: a sweep stopped midway has every row.
    assert [_seed(j) for j in jobs] == sorted(_seed(j) for j in jobs)
    assert [_cell(j) for j in jobs[:len(cells)]] == [p.cell for p in paper_rows(PAPER_TABLE[experiment])]
    job_cfg = _compose(*jobs[-1])  # a job composes as the sweep will run it
    assert job_cfg.name == experiment and job_cfg.cell == _cell(jobs[-1])
    assert (job_cfg.algorithm.name, job_cfg.representation.name) == LEARNER[experiment]
    run_spec(job_cfg)


def _cell(job: list[str]) -> str:
    return next(o.split("=", 1)[1] for o in job if o.startswith("cell="))


def _seed(job: list[str]) -> int:
    return int(next(o.split("=", 1)[1] for o in job if o.startswith("seed=")))


@pytest.mark.parametrize("group, name, cls", [
    (g, n, c) for g, options in schema.PYTHON_OPTIONS.items() for n, c in options.items()])
def test_python_configured_options_compose_to_their_dataclass_defaults(hydra_context, group, name, cls):
    # One place per default: the dataclass. The composed node holds exactly its fields and values
    # (Table I's tuned values aside, conf/tuned/, tested below).
    companions = {"dqn": ["representation=network"], "network": ["algorithm=dqn"]}
    node = _compose(f"{group}={name}", *companions.get(name, []), "tuned=provisional")[group]
    assert OmegaConf.get_type(node) is cls
    assert OmegaConf.to_container(node) == dataclasses.asdict(cls())


def test_no_yaml_file_repeats_a_python_default():
    # A Python-configured group has YAML options only as variants (conf/env/: readings of the
    # world): each extends one of the group's dataclass options and sets only what it changes.
    for group, options in schema.PYTHON_OPTIONS.items():
        for path in sorted((CONF_DIR / group).glob("*.yaml")):
            values = OmegaConf.to_container(OmegaConf.load(path))
            defaults = values.pop("defaults", None)
            assert path.stem not in options, f"{path} would be a second copy of {group}={path.stem}"
            assert defaults and defaults[0] in options and defaults[-1] == "_self_", path
            base = dataclasses.asdict(options[defaults[0]]())
            repeated = [k for k, v in values.items() if base.get(k) == v]
            assert values and not repeated, f"{path} repeats the defaults of {', '.join(repeated)}"


def test_network_representation_holds_no_keys_of_its_own(hydra_context):
    # The DQN's architecture lives in algorithm (DQNConfig); the factory refuses keys here.
    cfg = _compose("algorithm=dqn", "representation=network")
    assert OmegaConf.to_container(cfg.representation) == {"name": "network", "_target_": None}


def test_scales_match_the_paper_and_divide_the_budget(hydra_context):
    paper = _compose("scale=paper").scale
    assert (paper.budget, paper.seeds, paper.eval_points, paper.eval_episodes) == (500_000, 20, 25, 100)
    for scale in ("paper", "quick", "smoke"):
        run_spec(_compose(f"scale={scale}"))


def test_reduced_scales_report_beside_not_over_the_paper_scale(hydra_context):
    dirs = {scale: _compose(f"scale={scale}").paths.reports_dir for scale in ("paper", "quick", "smoke")}
    assert dirs == {"paper": "./reports", "quick": "./reports/quick", "smoke": "./reports/smoke"}


# --- bad overrides -----------------------------------------------------------------------------


@pytest.mark.parametrize("override, allowed", [
    ("algorithm=sarsa", ["linear_q", "dqn"]),
    ("scale=huge", ["paper", "quick", "smoke"]),
    ("cell=regular_7", ["none_0", "regular_50", "scaffolded_5000"]),
    ("experiment=table9", ["table2_rbf", "table3_fsr", "table4_dnn"]),
    ("n_source=abc", ["0", "1", "15", "50", "100", "5000"]),
    ("env=goal_radius_3", ["default", "goal_radius_1.5", "goal_radius_0.75", "far_annulus", "long_hook",
                           "tool_frame"]),
])
def test_unknown_option_is_one_line_naming_the_allowed_options(override, allowed):
    with pytest.raises(ConfigError) as error:
        compose_config([override])
    message = str(error.value)
    assert "\n" not in message and override.split("=")[0] in message
    assert all(a in message.split("allowed: ")[1].split(", ") for a in allowed)


@pytest.mark.parametrize("override, message", [
    ("+algoritm=dqn", "unknown key 'algoritm'; did you mean 'algorithm'?"),
    ("+foo=1", "unknown key 'foo'; keys here: name, cell, seed"),
    ("+scale.foo=1", "unknown key 'scale.foo'; keys here: name, budget"),
    ("+algorithm.no_such_key=1", "unknown key 'algorithm.no_such_key'"),
    ("algorithm.lamda_=0.5", "unknown key 'algorithm.lamda_'; did you mean 'algorithm.lambda_'?"),
    ("env.goal_radius=abc", "env.goal_radius=abc: Value 'abc' of type 'str' could not be converted to Float"),
    ("env.substeps=2.5", "env.substeps=2.5"),
    ("env.max_episode_steps=2.5", "env.max_episode_steps=2.5"),
    ("seed=abc", "seed=abc"),
    ("threshold=abc", "threshold=abc"),
])
def test_wrong_keys_and_types_are_refused_while_composing_in_one_line(override, message):
    with pytest.raises(ConfigError) as error:
        compose_config([override])
    assert message in str(error.value) and "\n" not in str(error.value)


def test_any_non_negative_n_source_composes():
    cfg = compose_config(["strategy=scaffolded", "n_source=7"])
    assert (cfg.n_source, cfg.cell) == (7, "scaffolded_7")
    assert run_spec(cfg).n_source == 7
    assert compose_config(["strategy=regular", "n_source=15"]).n_source == 15  # a paper option


@pytest.mark.parametrize("overrides, message", [
    (["algorithm=dqn", "representation=rbf"], "network"),
    (["algorithm=linear_q", "representation=network"], "rbf"),
    (["strategy=regular"], "n_source"),
    (["n_source=15"], "strategy"),
    (["scale.budget=201"], "eval_points"),
    (["env.goal_radius=20"], "goal_radius"),
    (["algorithm.gamma=1.5"], r"algorithm.gamma must lie in \[0, 1\), got 1.5"),
    (["seed=-1"], "seed must be >= 0"),
    (["algorithm=dqn", "representation=network", "algorithm.kernels=turbo"],
     r"^algorithm.kernels must be fast or reference, got 'turbo'$"),
    (["env.move_frame=polar"], r"^env.move_frame must be one of radial, tool, got 'polar'$"),
    (["env=tool_frame", "env.move_frame=1"], r"^env.move_frame must be one of radial, tool, got '1'$"),
])
def test_invalid_combination_fails_before_any_work(hydra_context, overrides, message):
    with pytest.raises(ConfigError, match=message):
        run_spec(_compose(*overrides))


def test_command_line_reports_an_invalid_combination_and_starts_nothing(tmp_path):
    from .test_sweep import _run_cli

    common = [f"paths.root={tmp_path}", "tracking=none", "scale=smoke"]
    with pytest.raises(SystemExit, match="Invalid configuration: .*allowed: network"):
        _run_cli("algorithm=dqn", "representation=rbf", *common)
    with pytest.raises(SystemExit, match="Invalid configuration: .*allowed: network"):
        _run_cli("experiment=table2_rbf", "algorithm=dqn", "hydra/launcher=basic", *common)
    assert not list(tmp_path.iterdir())  # failed before the first folder was made


def test_command_line_refuses_typos_and_bad_values_before_any_folder(tmp_path):
    from .test_sweep import _run_cli

    common = [f"paths.root={tmp_path}", "tracking=none", "scale=smoke"]
    for bad, key in [("+algoritm=dqn", "algorithm"), ("+foo=1", "foo"), ("env.goal_radius=abc", "env.goal_radius"),
                     ("algorithm.gamma=1.5", "algorithm.gamma")]:
        with pytest.raises(SystemExit) as error:
            _run_cli(bad, *common)
        assert str(error.value).startswith("Invalid configuration: ") and key in str(error.value)
        assert "\n" not in str(error.value)
    with pytest.raises(SystemExit, match="env.goal_radius"):
        _run_cli("-m", "experiment=table2_rbf", "env.goal_radius=abc", "hydra/launcher=basic", *common)
    assert not list(tmp_path.iterdir())


def test_numeric_group_choices_are_quoted_for_hydra():
    assert prepare_overrides(["n_source=15", "seed=3"]) == ["n_source='15'", "seed=3"]
    assert prepare_overrides(["n_source=1,15"]) == ["n_source='1','15'"]
    assert prepare_overrides(["n_source='15'", "scale.budget=10"]) == ["n_source='15'", "scale.budget=10"]
    assert prepare_overrides(["n_source='7'"]) == ["n_source='7'"]
    assert prepare_overrides(["n_source=choice(7,8)"]) == ["n_source='7','8'"]
    assert prepare_overrides(["n_source=range(1,3)"]) == ["n_source='1','2'"]
    assert prepare_overrides(["n_source=1, 7"]) == ["n_source='1','7'"]
    for bad, message in [("n_source=-1", "or any other integer >= 0"), ("n_source=interval(1,2)", "integers"),
                         ("key=[unclosed", "key=[unclosed"), ("tuned=xx", "allowed: ")]:
        with pytest.raises(ConfigError, match=re.escape(message)):
            prepare_overrides([bad])


def _tuned_files():
    return sorted(p for p in (CONF_DIR / "tuned").glob("*.yaml") if p.stem != "provisional")


def _learner_of(stem: str) -> tuple[str, str]:
    """(algorithm, representation) whose tuned values the file ``stem`` holds: the learner's own
    file (linear_q_fsr) or an earlier choice kept runnable (linear_q_fsr_round1)."""
    learners = [(a, r) for a in schema.PYTHON_OPTIONS["algorithm"] for r in schema.PYTHON_OPTIONS["representation"]]
    matches = [(a, r) for a, r in learners if stem == f"{a}_{r}" or stem.startswith(f"{a}_{r}_")]
    assert matches, f"conf/tuned/{stem}.yaml names no learner <algorithm>_<representation>"
    return max(matches, key=lambda m: len(f"{m[0]}_{m[1]}"))


@pytest.mark.parametrize("path", _tuned_files(), ids=lambda p: p.stem)
def test_tuned_values_apply_to_their_learner_only_and_are_searched_keys(path):
    from mediated_transfer.tuning.space import available_learners, load_search_space

    algorithm, representation = _learner_of(path.stem)
    tuned = OmegaConf.to_container(OmegaConf.load(path))
    values = {f"{group}.{key}": v for group, keys in tuned.items() for key, v in keys.items()}
    assert values, f"{path.name} sets no value"
    # The learner's own file applies by default; an earlier choice when named (tuned=<stem>).
    chosen = [] if path.stem == f"{algorithm}_{representation}" else [f"tuned={path.stem}"]
    learner = compose_config([f"algorithm={algorithm}", f"representation={representation}", *chosen])
    provisional = compose_config([f"algorithm={algorithm}", f"representation={representation}", "tuned=provisional"])
    for key, value in values.items():
        assert OmegaConf.select(learner, key) == value
        group, field = key.split(".")
        option = schema.PYTHON_OPTIONS[group][learner[group].name]
        assert OmegaConf.select(provisional, key) == getattr(option(), field)
    # A study's trials override every searched key, so tuned values must be searched keys, or
    # a setting the search held fixed in its base, at the same value (PPO's 8 environments: what
    # was tuned is what runs).
    spaces = [load_search_space(p) for p in available_learners().values()]
    [space] = [s for s in spaces if {f"algorithm={algorithm}", f"representation={representation}"} <= set(s.base)]
    fixed = dict(o.split("=", 1) for o in space.base if "." in o.split("=", 1)[0])
    for key, value in values.items():
        assert key in {p.key for p in space.params} or fixed.get(key) == str(value), (path.name, key)
    # Every value names where it comes from.
    text = path.read_text()
    assert all(f"{key.split('.')[1]}:" in text for key in values) and "refine" in text


def test_a_run_made_before_a_key_existed_is_the_same_run_but_another_value_is_not(tmp_path):
    from omegaconf import OmegaConf

    from mediated_transfer.provenance.judge import check_same_run
    from mediated_transfer.results import RunResult

    cfg = compose_config(["experiment=table2_rbf", "cell=none_0", "seed=0"])
    recorded = OmegaConf.to_container(cfg, resolve=True)
    del recorded["algorithm"]["max_rollback_share"]  # a key added after the run was made
    result = RunResult(algorithm="linear_q", representation="rbf", strategy="none", n_source=0, seed=0,
                       budget=200, steps=[100, 200], mean_reward=[0.0, 0.0], success_rate=[0.0, 0.0],
                       reward_loss=20.0, time_to_threshold=None, source_phase_end=None,
                       source_tasks_solved=0, wall_time_s=1.0, learning_steps_per_s=200.0,
                       learner_stats={}, config=recorded)
    check_same_run(result, run_spec(cfg), tmp_path)  # no error
    recorded["algorithm"]["max_rollback_share"] = 0.5
    with pytest.raises(ConfigError, match="max_rollback_share: stored 0.5, now 0.1"):
        check_same_run(result, run_spec(cfg), tmp_path)
