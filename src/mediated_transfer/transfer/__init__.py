"""Transfer from source tasks: the clustered source task set C, the strategies that use it, and
the strategies as a Gymnasium wrapper for any learner."""

from .source_tasks import precompute_source_task_sets, sensor_vectors, source_task_set
from .strategies import STRATEGIES, TransferStrategy, make_strategy
from .wrapper import TransferWrapper

__all__ = ["STRATEGIES", "TransferStrategy", "TransferWrapper", "make_strategy",
           "precompute_source_task_sets", "sensor_vectors", "source_task_set"]
