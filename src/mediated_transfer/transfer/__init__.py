"""Transfer from source tasks: the clustered source task set C and the strategies that use it."""

from .source_tasks import precompute_source_task_sets, sensor_vectors, source_task_set
from .strategies import STRATEGIES, TransferStrategy, make_strategy

__all__ = ["STRATEGIES", "TransferStrategy", "make_strategy", "precompute_source_task_sets",
           "sensor_vectors", "source_task_set"]
