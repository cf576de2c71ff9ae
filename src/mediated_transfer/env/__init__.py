"""The paper's 2D world: an agent, a disc-shaped target and an L-shaped tool (the mediator).

Importing this package registers the Gymnasium id ``ENV_ID``:
``gymnasium.make("mediated_transfer/MediatedInteraction-v0", scenario="source")``.
"""

import gymnasium

from .config import WorldConfig
from .mediated_env import ACTION_NAMES, NUM_ACTIONS, MediatedInteractionEnv
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

ENV_ID = "mediated_transfer/MediatedInteraction-v0"

# The entry point is a string, so making the environment imports nothing more than this did;
# the guard keeps a re-import from re-registering (Gymnasium would warn).
if ENV_ID not in gymnasium.registry:
    # The episode limit is the paper's 100 steps (WorldConfig.max_episode_steps), declared so
    # that env.spec.max_episode_steps tells learners and wrappers; the environment truncates at
    # its own config's limit, so a world with another limit needs max_episode_steps= here too
    # (a larger one, or -1, is refused: make.check_episode_limit). make.make_env refuses
    # render_mode="human" without pygame at once.
    gymnasium.register(
        id=ENV_ID, entry_point="mediated_transfer.env.make:make_env",
        max_episode_steps=WorldConfig.max_episode_steps,
        additional_wrappers=(gymnasium.envs.registration.WrapperSpec(
            "check_episode_limit", "mediated_transfer.env.make:check_episode_limit", {}),),
    )

__all__ = [
    "ACTION_NAMES", "ENV_ID", "M1", "M2", "M3", "T", "O", "NUM_ACTIONS", "NUM_DISTANCES",
    "OBSERVATION_SIZE", "PICKING_LOCATIONS", "SCENARIOS", "MediatedInteractionEnv", "Task",
    "WorldConfig", "sample_task", "sample_tasks", "sensor_vector", "tool_picking_locations",
]
