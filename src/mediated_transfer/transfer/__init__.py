"""Transfer from source tasks: the clustered source task set C, the strategy interface and the
paper's strategies, and the strategies as a Gymnasium wrapper for any learner."""

from .source_tasks import precompute_source_task_sets, sensor_vectors, source_task_set
from .strategies import NoTransfer, RegularTransfer, ScaffoldedTransfer
from .strategy import EpisodeOutcome, Strategy, StrategyContext, make_strategy
from .wrapper import TransferWrapper

__all__ = ["EpisodeOutcome", "NoTransfer", "RegularTransfer", "ScaffoldedTransfer", "Strategy",
           "StrategyContext", "TransferWrapper", "make_strategy", "precompute_source_task_sets", "sensor_vectors",
           "source_task_set"]
