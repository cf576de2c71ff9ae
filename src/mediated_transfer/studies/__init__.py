"""One shape for a study: registration -> runs -> measures -> report (shape.py), one driver that
builds it (``build``), and the command-line plumbing every study's command shares (command.py).

Table I (tuning/table1.py), the tables' reproduction report (reporting/reproduction/), the DQN
failure ablation (reporting/ablation.py), the sensitivity study (sensitivity/) and the curricula
study (curricula/) are each one ``Study``: where its registered rules live, the stored runs it
reads, the numbers it measures from them, and the report those numbers give.
"""

from .command import command, split_options
from .registration import added_in
from .shape import Study, Written, build, stale_runs

__all__ = ["Study", "Written", "added_in", "build", "command", "split_options", "stale_runs"]
