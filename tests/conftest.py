"""Without the deep extra (torch, Stable-Baselines3), each test parametrized with a deep
learner's option skips, e.g. ``test_run.py::...[dqn-network]`` (tests/optional.py)."""

from __future__ import annotations

import signal

import pytest

from .optional import DEEP, REASON, deep_option

# A suite started in the background (`cmd &` in a script) has SIGINT ignored, and so would every
# process it starts: the tests that stop a sweep as Ctrl-C does need SIGINT as a terminal has it.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    # The slow tests first (order otherwise kept): spread over the workers from the start, they
    # do not leave one worker running a long sweep while the others are done.
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)
    if DEEP:
        return
    for item in items:
        callspec = getattr(item, "callspec", None)
        if callspec is not None and any(deep_option(v) for v in callspec.params.values()):
            item.add_marker(pytest.mark.skip(reason=REASON))


@pytest.fixture(autouse=True)
def _no_search_path_of_an_earlier_test():
    """The config search path is the last composed config's (config/compose.py): a test that
    composed a plugin's must not lend its options to the next test of the same worker."""
    from mediated_transfer.config import compose

    compose._SEARCH_DIRS.clear()
    yield
    compose._SEARCH_DIRS.clear()
