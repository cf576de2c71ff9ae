"""``python -m mediated_transfer --help``: Hydra's help, listing the options of the command's
``hydra.searchpath`` too.

Hydra lists a group's options from its search path as the application starts (conf/ and the
search path plugins), before the command's ``hydra.searchpath`` override is read, so a plugin's
options (``strategy=easy_first``) would be missing from the list while the command accepts
them. Here the help is Hydra's own, from a Hydra whose search path already holds those folders.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from .compose import CONF_DIR, CONFIG_NAME
from .searchpath import searchpath_entries

TASK_NAME = "mediated_transfer"


def app_help(args: argparse.Namespace, overrides: Sequence[str]) -> None:
    """Print the help of ``overrides`` (prepared: compose.prepare_overrides, which checked the
    search path), as Hydra's ``--help`` prints it."""
    from hydra._internal.hydra import Hydra
    from hydra._internal.utils import create_config_search_path, get_args_parser, run_and_report
    from hydra.core.config_search_path import SearchPathQuery
    from hydra.core.global_hydra import GlobalHydra

    search_path = create_config_search_path(f"file://{CONF_DIR}")
    for entry in searchpath_entries(overrides):
        search_path.prepend(provider="hydra.searchpath in command-line", path=entry,
                            anchor=SearchPathQuery(provider="schema"))
    GlobalHydra.instance().clear()
    try:
        hydra = run_and_report(lambda: Hydra.create_main_hydra2(task_name=TASK_NAME, config_search_path=search_path))
        shown = argparse.Namespace(**{**vars(args), "overrides": list(overrides)})
        run_and_report(lambda: hydra.app_help(config_name=CONFIG_NAME, args_parser=get_args_parser(), args=shown))
    finally:
        GlobalHydra.instance().clear()
