"""The paper's 2D world: an agent, a disc-shaped target and an L-shaped tool (the mediator)."""

from .config import WorldConfig
from .task import (
    M1,
    M2,
    M3,
    NUM_DISTANCES,
    O,
    OBSERVATION_SIZE,
    PICKING_LOCATIONS,
    SCENARIOS,
    T,
    Task,
    sample_task,
    sample_tasks,
    sensor_vector,
    tool_picking_locations,
)

__all__ = [
    "M1", "M2", "M3", "T", "O", "NUM_DISTANCES", "OBSERVATION_SIZE", "PICKING_LOCATIONS",
    "SCENARIOS", "Task", "WorldConfig", "sample_task", "sample_tasks", "sensor_vector",
    "tool_picking_locations",
]
