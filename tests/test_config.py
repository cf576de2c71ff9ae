"""conf/: every group option composes into a runnable config, the YAML defaults agree with the
dataclasses they configure, each experiment's sweep covers exactly its table's rows, and bad
overrides fail at once with a message naming the allowed values."""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import textwrap

import pytest
from hydra import compose, initialize_config_dir
from hydra.errors import ConfigCompositionException, MissingConfigException
from hydra.utils import get_class
from omegaconf import OmegaConf

from mediated_transfer.app import CONF_DIR, ConfigError, planned_jobs, quote_numeric_choices, run_spec
from mediated_transfer.reporting.paper import paper_rows

# conf file -> the dataclass whose fields and defaults it spells out.
DATACLASS_OF = {
    "env/default": "mediated_transfer.env.config.WorldConfig",
    "algorithm/linear_q": "mediated_transfer.learners.linear_q.LinearQConfig",
    "algorithm/dqn": "mediated_transfer.learners.dqn.DQNConfig",
    "representation/rbf": "mediated_transfer.learners.rbf.RBFConfig",
    "representation/fsr": "mediated_transfer.learners.fsr.FSRConfig",
}
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
    return compose("config", overrides=quote_numeric_choices(overrides), return_hydra_config=hydra)


# Not groups of a run: Hydra's own, whole experiments, and the tuning's search spaces (read by
# mediated_transfer.tuning, checked in tests/test_tuning.py).
NOT_RUN_GROUPS = ("hydra", "experiment", "hparams_search")


def _options() -> list[str]:
    out = []
    for group in sorted(p for p in CONF_DIR.iterdir() if p.is_dir() and p.name not in NOT_RUN_GROUPS):
        out += [f"{group.name}={option.stem}" for option in sorted(group.glob("*.yaml"))]
    return out


def _companions(option: str) -> list[str]:
    group, name = option.split("=")
    if group == "n_source" and name != "0":
        return ["strategy=regular"]
    return COMPANIONS.get(option, [])


@pytest.mark.parametrize("option", _options())
def test_every_group_option_composes_into_a_valid_run(hydra_context, option):
    cfg = _compose(option, *_companions(option))
    OmegaConf.to_container(cfg, resolve=True)  # every interpolation resolves
    spec = run_spec(cfg)
    group, name = option.split("=")
    if group in ("algorithm", "representation"):
        assert getattr(spec, group) == name
    if group == "cell":
        assert f"{spec.strategy}_{spec.n_source}" == name == cfg.cell
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
    from mediated_transfer.tracking import TrackingSettings

    cfg = _compose(option, *_companions(option), f"paths.root={tmp_path}")
    if cfg.tracking.enabled:
        settings = TrackingSettings.from_config(cfg.tracking)
        assert settings.uri.startswith(("sqlite:///", "http://"))
    else:
        assert option == "tracking=none"


@pytest.mark.parametrize("launcher, target", [
    ("parallel", "hydra_plugins.hydra_joblib_launcher.joblib_launcher.JoblibLauncher"),
    ("submitit_local", "hydra_plugins.hydra_submitit_launcher.submitit_launcher.LocalLauncher"),
    ("slurm", "hydra_plugins.hydra_submitit_launcher.submitit_launcher.SlurmLauncher"),
    ("basic", "hydra._internal.core_plugins.basic_launcher.BasicLauncher"),
])
def test_launcher_presets_compose_and_name_an_importable_launcher(hydra_context, launcher, target):
    cfg = _compose(f"hydra/launcher={launcher}", hydra=True)
    assert cfg.hydra.launcher._target_ == target
    get_class(target)


def test_default_launcher_is_joblib_with_one_worker_per_core(hydra_context):
    launcher = _compose(hydra=True).hydra.launcher
    assert launcher._target_.endswith("JoblibLauncher") and launcher.n_jobs == -1


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
    job_cfg = _compose(*jobs[-1])  # a job composes as the sweep will run it
    assert job_cfg.name == experiment and job_cfg.cell == _cell(jobs[-1])
    assert (job_cfg.algorithm.name, job_cfg.representation.name) == LEARNER[experiment]
    run_spec(job_cfg)


def _cell(job: list[str]) -> str:
    return next(o.split("=", 1)[1] for o in job if o.startswith("cell="))


def _seed(job: list[str]) -> int:
    return int(next(o.split("=", 1)[1] for o in job if o.startswith("seed=")))


@pytest.mark.parametrize("name", sorted(DATACLASS_OF))
def test_yaml_defaults_equal_the_dataclass_defaults(name):
    cls = _import(DATACLASS_OF[name])
    yaml = OmegaConf.to_container(OmegaConf.load(CONF_DIR / f"{name}.yaml"))
    yaml.pop("name", None)
    defaults = {f.name: _default(f) for f in dataclasses.fields(cls)}
    assert yaml == defaults, (
        f"conf/{name}.yaml is out of date with {cls.__name__}; its body should read:\n"
        + dataclass_yaml(cls))


def test_network_representation_holds_no_keys_of_its_own():
    # The DQN's architecture lives in algorithm/dqn.yaml; the factory refuses keys here.
    assert OmegaConf.to_container(OmegaConf.load(CONF_DIR / "representation/network.yaml")) == {"name": "network"}


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
    ("n_source=7", ["0", "1", "15", "50", "100", "5000"]),
    ("algorithm=sarsa", ["linear_q", "dqn"]),
    ("scale=huge", ["paper", "quick", "smoke"]),
    ("cell=regular_7", ["none_0", "regular_50", "scaffolded_5000"]),
    ("experiment=table9", ["table2_rbf", "table3_fsr", "table4_dnn"]),
])
def test_unknown_option_names_the_allowed_options(hydra_context, override, allowed):
    with pytest.raises(MissingConfigException) as error:
        _compose(override)
    assert all(f"\t{a}\n" in str(error.value) for a in allowed)


def test_unknown_key_is_refused(hydra_context):
    with pytest.raises(ConfigCompositionException, match="algorithm.no_such_key"):
        _compose("algorithm.no_such_key=1")


@pytest.mark.parametrize("overrides, message", [
    (["algorithm=dqn", "representation=rbf"], "network"),
    (["algorithm=linear_q", "representation=network"], "rbf"),
    (["strategy=regular"], "n_source"),
    (["n_source=15"], "strategy"),
    (["scale.budget=201"], "eval_points"),
    (["env.goal_radius=20"], "goal_radius"),
    (["+algorithm.no_such_key=1"], "no_such_key"),
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


def test_numeric_group_choices_are_quoted_for_hydra():
    groups = {"n_source"}
    assert quote_numeric_choices(["n_source=15", "seed=3"], groups) == ["n_source='15'", "seed=3"]
    assert quote_numeric_choices(["n_source=1,15"], groups) == ["n_source='1','15'"]
    assert quote_numeric_choices(["n_source='15'", "scale.budget=10"], groups) == ["n_source='15'", "scale.budget=10"]


# --- helpers -----------------------------------------------------------------------------------


def _import(path: str):
    module, name = path.rsplit(".", 1)
    return getattr(importlib.import_module(module), name)


def _default(field):
    return field.default if field.default is not dataclasses.MISSING else field.default_factory()


def dataclass_yaml(cls) -> str:
    """The YAML body for ``cls``: each field's docstring as a comment, then key: default."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body
    docs = {a.target.id: " ".join(b.value.value.split()) for a, b in zip(body, body[1:])
            if isinstance(a, ast.AnnAssign) and isinstance(b, ast.Expr) and isinstance(b.value, ast.Constant)}
    lines = []
    for f in dataclasses.fields(cls):
        lines += ["# " + line for line in textwrap.wrap(docs.get(f.name, ""), 96)]
        lines.append(f"{f.name}: {OmegaConf.to_yaml({f.name: _default(f)}).split(': ', 1)[1].strip()}")
    return "\n".join(lines) + "\n"


def rewrite_yaml(name: str) -> None:
    """Replace the body of conf/<name>.yaml by the dataclass's fields, keeping its header
    (everything up to the first blank line)."""
    path = CONF_DIR / f"{name}.yaml"
    header = path.read_text().split("\n\n", 1)[0]
    path.write_text(header + "\n\n" + dataclass_yaml(_import(DATACLASS_OF[name])))


if __name__ == "__main__":
    # python -m tests.test_config: bring the YAML files up to date after a dataclass changed.
    for conf_name in DATACLASS_OF:
        rewrite_yaml(conf_name)
        print(f"wrote conf/{conf_name}.yaml")
