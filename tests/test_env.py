"""The Gymnasium environment: API, exact observations, action semantics, physics, bad input."""

import importlib.util
import math

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import mediated_transfer  # noqa: F401  (registers the environment)
from mediated_transfer.env import ENV_ID, M1, M2, M3, O, T, MediatedInteractionEnv, Task, WorldConfig
from mediated_transfer.env.mediated_env import (
    MOVE_CCW,
    MOVE_CW,
    MOVE_IN,
    MOVE_OUT,
    NUM_ACTIONS,
    PICK_M1,
    PICK_M2,
    PICK_M3,
    PICK_O,
    PICK_T,
    ROTATE_CCW,
    ROTATE_CW,
)

NOISELESS = WorldConfig(action_noise=0.0)
MOVES_AND_TURNS = (MOVE_OUT, MOVE_IN, MOVE_CCW, MOVE_CW, ROTATE_CCW, ROTATE_CW)
# M1 (11, 3) and the target (12, 0) out of reach; M2 (4, 3) and M3 (4, 6.5) in reach.
HAND_BUILT = Task((12.0, 0.0), (4.0, 3.0), 0.0)


def make(task=HAND_BUILT, config=NOISELESS, scenario="target"):
    env = MediatedInteractionEnv(scenario, config)
    env.reset(seed=0, options={"task": task})
    return env


def rollout(env, seed, steps=150, action_seed=7):
    rng = np.random.default_rng(action_seed)
    observations = [env.reset(seed=seed)[0]]
    for _ in range(steps):
        observation, reward, terminated, truncated, _ = env.step(int(rng.integers(NUM_ACTIONS)))
        observations.append(observation)
        if terminated or truncated:
            observations.append(env.reset()[0])
    return np.array(observations)


# --- Gymnasium API ------------------------------------------------------------------------------
@pytest.mark.parametrize("scenario", ["source", "target"])
def test_env_checker_passes(scenario):
    env = gymnasium.make(ENV_ID, scenario=scenario)
    check_env(env.unwrapped)


def test_registered_id_makes_the_environment_with_kwargs():
    env = gymnasium.make(
        "mediated_transfer/MediatedInteraction-v0", scenario="source", config={"goal_radius": 1.5}
    )
    assert env.unwrapped.scenario == "source"
    assert env.unwrapped.config.goal_radius == 1.5
    observation, info = env.reset(seed=1)
    assert env.observation_space.contains(observation)
    assert info == {"active_location": O, "is_success": False}


def test_same_seed_same_rollout_and_no_memory_of_earlier_episodes():
    first = rollout(MediatedInteractionEnv(), seed=3)
    again = rollout(MediatedInteractionEnv(), seed=3)
    np.testing.assert_array_equal(first, again)
    # An environment that already ran other episodes (and cached contacts) replays it exactly.
    used = MediatedInteractionEnv()
    rollout(used, seed=11, steps=300)
    np.testing.assert_array_equal(rollout(used, seed=3), first)
    assert not np.array_equal(rollout(MediatedInteractionEnv(), seed=4), first)


def test_observations_stay_in_the_box_under_random_actions():
    env = MediatedInteractionEnv("target")
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    for _ in range(3000):
        observation, _, terminated, truncated, _ = env.step(int(rng.integers(NUM_ACTIONS)))
        assert env.observation_space.contains(observation)
        assert observation[6:].sum() == 1.0
        if terminated or truncated:
            env.reset()


# --- observation --------------------------------------------------------------------------------
def test_exact_observation_on_a_hand_built_task():
    env = MediatedInteractionEnv("target", NOISELESS)
    observation, _ = env.reset(options={"task": HAND_BUILT})
    distances = [
        math.sqrt(1**2 + 3**2),  # |M1 T|: (11, 3) to (12, 0)
        math.sqrt(8**2 + 3**2),  # |M2 T|: (4, 3)
        math.sqrt(8**2 + 6.5**2),  # |M3 T|: (4, 6.5)
        math.sqrt(11**2 + 3**2),  # |M1 O|
        5.0,  # |M2 O|
        math.sqrt(4**2 + 6.5**2),  # |M3 O|
    ]
    np.testing.assert_allclose(observation, distances + [0, 0, 0, 0, 1], rtol=1e-12)
    observation, *_ = env.step(PICK_M3)
    np.testing.assert_allclose(observation, distances + [0, 0, 1, 0, 0], rtol=1e-12)
    np.testing.assert_allclose(env.picking_locations, [[11, 3], [4, 3], [4, 6.5], [12, 0], [0, 0]])


def test_reset_accepts_task_coordinates():
    env = MediatedInteractionEnv("source", NOISELESS)
    observation, _ = env.reset(options={"task": HAND_BUILT.coordinates.tolist()})
    np.testing.assert_allclose(observation, HAND_BUILT.sensor_vector(NOISELESS))
    assert env.task == HAND_BUILT


# --- picking -------------------------------------------------------------------------------------
@pytest.mark.parametrize("pick", [PICK_M1, PICK_T])
def test_picking_out_of_range_changes_nothing(pick):
    env = make()
    before = (env.picking_locations, env.tool_angle, env.physics_steps)
    observation, reward, terminated, truncated, info = env.step(pick)
    assert env.active_location == O and info["active_location"] == O
    np.testing.assert_array_equal(observation, HAND_BUILT.sensor_vector(NOISELESS))
    np.testing.assert_array_equal(env.picking_locations, before[0])
    assert (env.tool_angle, env.physics_steps) == before[1:]
    assert (reward, terminated, truncated) == (0.0, False, False)


@pytest.mark.parametrize("action", MOVES_AND_TURNS)
def test_origin_is_absorbing(action):
    env = make()
    env.step(PICK_M2)
    env.step(PICK_O)
    before = env.picking_locations
    observation, *_ = env.step(action)
    assert env.active_location == O
    np.testing.assert_array_equal(env.picking_locations, before)
    np.testing.assert_array_equal(observation, HAND_BUILT.sensor_vector(NOISELESS))


# --- moves and turns -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "action, m2_after",
    [
        (MOVE_OUT, (4.8, 3.6)),  # radial frame at M2 = (4, 3): u = (0.8, 0.6)
        (MOVE_IN, (3.2, 2.4)),
        (MOVE_CCW, (3.4, 3.8)),  # tangential: (-0.6, 0.8)
        (MOVE_CW, (4.6, 2.2)),
    ],
)
def test_a_move_carries_the_tool_one_unit_along_the_frame_at_the_active_location(action, m2_after):
    env = make()
    env.step(PICK_M2)
    env.step(action)
    shift = np.subtract(m2_after, (4.0, 3.0))
    expected = HAND_BUILT.picking_locations(NOISELESS)
    expected[:3] += shift
    np.testing.assert_allclose(env.picking_locations, expected, atol=1e-9)
    assert env.tool_angle == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("pick", [PICK_M1, PICK_M3])
def test_the_radial_frame_is_the_default_and_attached_at_the_held_location(pick):
    # The frame of today's environment, whichever location is held: out = away from O at it.
    task = Task((12.0, 0.0), (1.0, -2.0), math.pi / 3)  # the whole tool in reach
    for config in (NOISELESS, WorldConfig(action_noise=0.0, move_frame="radial")):
        env = make(task, config)
        env.step(pick)
        held = env.picking_locations[pick]
        u = held / np.linalg.norm(held)
        for action, direction in ((MOVE_OUT, u), (MOVE_CCW, np.array([-u[1], u[0]]))):
            before = env.picking_locations
            env.step(action)
            np.testing.assert_allclose(env.picking_locations[:3], before[:3] + direction, atol=1e-9)
            u = env.picking_locations[pick] / np.linalg.norm(env.picking_locations[pick])


TOOL_FRAME = WorldConfig(action_noise=0.0, move_frame="tool")
# The whole tool in reach: M2 (1, -2), handle at 60 degrees: M1 (4.5, 4.06), M3 (-2.03, -0.25).
TILTED = Task((12.0, 0.0), (1.0, -2.0), math.pi / 3)


@pytest.mark.parametrize("pick", [PICK_M1, PICK_M2, PICK_M3])
@pytest.mark.parametrize(
    "action, along",
    [
        (MOVE_OUT, (0.5, math.sqrt(3) / 2)),  # along the handle, M2 -> M1
        (MOVE_IN, (-0.5, -math.sqrt(3) / 2)),
        (MOVE_CCW, (-math.sqrt(3) / 2, 0.5)),  # along the hook, M2 -> M3
        (MOVE_CW, (math.sqrt(3) / 2, -0.5)),
    ],
)
def test_the_tool_frame_moves_a_held_tool_along_its_own_arms(pick, action, along):
    env = make(TILTED, TOOL_FRAME)
    env.step(pick)
    env.step(action)
    expected = TILTED.picking_locations(TOOL_FRAME)
    expected[:3] += along  # the same move whichever of M1, M2, M3 is held
    np.testing.assert_allclose(env.picking_locations, expected, atol=1e-9)
    assert env.tool_angle == pytest.approx(math.pi / 3, abs=1e-12)


def test_the_tool_frame_turns_with_the_tool():
    env = make(TILTED, TOOL_FRAME)
    env.step(PICK_M2)
    env.step(ROTATE_CCW)  # the handle now points at 105 degrees
    before = env.picking_locations
    env.step(MOVE_OUT)
    along = (math.cos(7 * math.pi / 12), math.sin(7 * math.pi / 12))
    np.testing.assert_allclose(env.picking_locations[:3], before[:3] + along, atol=1e-9)


def test_the_tool_frame_moves_the_target_radially():
    # The target's disc has no orientation: holding T keeps the radial frame.
    radial, tool = make(Task((5.0, 0.0), (-4.0, -3.0), 0.0)), make(Task((5.0, 0.0), (-4.0, -3.0), 0.0), TOOL_FRAME)
    for env in (radial, tool):
        env.step(PICK_T)
        env.step(MOVE_IN)
        env.step(MOVE_CCW)
    np.testing.assert_allclose(tool.target_position, [4.0, 1.0], atol=1e-9)
    np.testing.assert_array_equal(tool.picking_locations, radial.picking_locations)


def test_the_tool_frame_refuses_moves_out_of_range_and_through_the_wall():
    config = WorldConfig(action_noise=0.0, move_frame="tool", tool_handle_length=8.5)
    env = make(Task((-12.0, 0.0), (9.0, 0.0), 0.0), config)  # M1 at (17.5, 0) beyond reach
    env.step(PICK_M2)
    before = env.picking_locations
    env.step(MOVE_OUT)  # M2 would stay in reach (10), M1 would pass the wall (18.5 > 17.75)
    np.testing.assert_array_equal(env.picking_locations, before)
    env.step(MOVE_IN)
    env.step(MOVE_IN)  # M2 at (7, 0)
    env.step(PICK_M3)  # M3 at (7, 3.5)
    env.step(MOVE_IN)  # along -handle: M3 to (6, 3.5)
    np.testing.assert_allclose(env.picking_locations[M3], [6.0, 3.5], atol=1e-9)
    env = make(Task((-12.0, 0.0), (9.5, 0.0), 0.0), TOOL_FRAME)
    env.step(PICK_M2)
    before = env.picking_locations
    env.step(MOVE_OUT)  # M2 would leave the range (10.5)
    np.testing.assert_array_equal(env.picking_locations, before)


def test_the_tool_frame_hooks_the_target_by_pulling_along_the_handle():
    # Handle towards O, the hook behind the out-of-reach target: "out" along the handle pulls.
    env = make(Task((12.0, 0.0), (13.5, 1.3), math.pi), TOOL_FRAME)
    env.step(PICK_M1)
    for _ in range(3):
        env.step(MOVE_OUT)
    assert np.linalg.norm(env.target_position) < 10.0
    env.step(PICK_T)
    assert env.active_location == T


@pytest.mark.parametrize("action, turn", [(ROTATE_CCW, math.pi / 4), (ROTATE_CW, -math.pi / 4)])
@pytest.mark.parametrize("pivot", [PICK_M2, PICK_M3])
def test_a_turn_rotates_the_tool_around_the_active_location(action, turn, pivot):
    env = make()
    env.step(pivot)
    fixed = env.picking_locations[pivot]
    env.step(action)
    assert env.tool_angle == pytest.approx(turn, abs=1e-9)
    np.testing.assert_allclose(env.picking_locations[pivot], fixed, atol=1e-9)
    expected = Task(HAND_BUILT.target_position, tuple(env.tool_position), turn)
    np.testing.assert_allclose(env.picking_locations, expected.picking_locations(NOISELESS), atol=1e-9)


def test_the_target_moves_but_never_turns():
    env = make(Task((5.0, 0.0), (-4.0, -3.0), 0.0))
    env.step(PICK_T)
    for action in (ROTATE_CCW, ROTATE_CW):
        env.step(action)
        np.testing.assert_array_equal(env.target_position, [5.0, 0.0])
    env.step(MOVE_IN)
    np.testing.assert_allclose(env.target_position, [4.0, 0.0], atol=1e-9)


def test_a_move_out_of_range_is_refused():
    env = make(Task((12.0, 0.0), (0.0, -9.5), math.pi / 2))
    env.step(PICK_M2)
    before = env.picking_locations
    env.step(MOVE_OUT)  # M2 would reach 10.5
    np.testing.assert_array_equal(env.picking_locations, before)
    env.step(MOVE_CW)  # to sqrt(9.5^2 + 1) < 10: allowed
    assert np.linalg.norm(env.picking_locations[M2]) == pytest.approx(math.hypot(9.5, 1.0))


def test_a_turn_through_the_wall_is_refused():
    env = make(Task((-12.0, 0.0), (16.9, 0.0), math.pi))  # handle end M1 at (9.9, 0), in reach
    env.step(PICK_M1)
    env.step(MOVE_CW)  # the hook's end M3 now lies at 17.49 from O
    before = env.picking_locations
    env.step(ROTATE_CCW)  # would swing M3 beyond the wall (limit 17.75)
    np.testing.assert_array_equal(env.picking_locations, before)
    env.step(ROTATE_CW)  # swings the hook inwards: allowed
    assert not np.allclose(env.picking_locations, before)


# --- physics -------------------------------------------------------------------------------------
def test_the_hook_drags_the_target_into_reach():
    # Handle towards O, the hook behind the out-of-reach target, M1 (6.5, 1.3) in reach.
    env = make(Task((12.0, 0.0), (13.5, 1.3), math.pi))
    env.step(PICK_M1)
    env.step(PICK_T)
    assert env.active_location == M1  # T (12 from O) cannot be picked yet
    for _ in range(3):
        env.step(MOVE_IN)
    target = env.target_position
    assert np.linalg.norm(target) < 10.0  # pulled in by contact alone
    hook = env.picking_locations[M3]
    assert target[0] < hook[0]  # still in front of the hook
    env.step(PICK_T)
    assert env.active_location == T


def test_the_target_pushes_the_tool_and_a_pushed_grip_is_lost():
    # The target (in reach) is pushed into the hook; the coasting tool carries M3 out of reach
    # during the very step in which M3 was picked.
    env = make(Task((6.8, 1.75), (8.3, 0.0), 0.0))
    env.step(PICK_T)
    env.step(MOVE_OUT)
    m3 = env.picking_locations[M3]
    assert np.linalg.norm(m3) < NOISELESS.interaction_radius
    assert np.linalg.norm(m3) > math.hypot(8.3, 3.5)  # pushed
    _, _, _, _, info = env.step(PICK_M3)
    assert np.linalg.norm(env.picking_locations[M3]) > NOISELESS.interaction_radius
    assert env.active_location == O and info["active_location"] == O


# --- reward and episode end ------------------------------------------------------------------------
def test_success_gives_the_reward_and_terminates():
    env = make(Task((2.5, 0.0), (-5.0, -5.0), 0.0))
    env.step(PICK_T)
    observation, reward, terminated, truncated, info = env.step(MOVE_IN)
    assert (reward, terminated, truncated) == (NOISELESS.success_reward, True, False)
    assert info["is_success"]
    with pytest.raises(RuntimeError, match="reset"):
        env.step(PICK_O)


def test_truncation_at_the_step_limit():
    env = make()
    for step in range(1, NOISELESS.max_episode_steps + 1):
        _, reward, terminated, truncated, _ = env.step(PICK_O)
        assert truncated == (step == NOISELESS.max_episode_steps)
        assert not terminated and reward == 0.0
    assert env.elapsed_steps == NOISELESS.max_episode_steps


def test_action_noise_replaces_actions_from_the_seeded_generator():
    def actives(seed):
        env = MediatedInteractionEnv("source", WorldConfig(action_noise=1.0))
        env.reset(seed=seed, options={"task": HAND_BUILT})
        return [env.step(PICK_O)[4]["active_location"] for _ in range(60)]

    assert actives(0) == actives(0)
    assert set(actives(0)) - {O}  # always asking for O, yet other locations became active
    assert actives(0) != actives(1)


# --- bad input -----------------------------------------------------------------------------------
def test_unknown_scenario_lists_the_allowed_ones():
    with pytest.raises(ValueError, match="'mediated'.*source, target"):
        MediatedInteractionEnv("mediated")


def test_bad_render_mode_and_config_are_named():
    with pytest.raises(ValueError, match="render_mode 'human'.*rgb_array"):
        MediatedInteractionEnv(render_mode="human")
    with pytest.raises(ValueError, match="goal_radiuss.*goal_radius"):
        MediatedInteractionEnv(config={"goal_radiuss": 1.0})
    with pytest.raises(ValueError, match="env.substeps"):
        MediatedInteractionEnv(config={"substeps": 0})
    with pytest.raises(ValueError, match="^env.move_frame must be one of radial, tool, got 'polar'$"):
        MediatedInteractionEnv(config={"move_frame": "polar"})
    with pytest.raises(ValueError, match="env.move_frame must be one of radial, tool, got 1"):
        WorldConfig(move_frame=1)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"tasks": HAND_BUILT}, "unknown reset option.*tasks.*allowed: task"),
        ({"task": HAND_BUILT, "seed": 1}, "unknown reset option.*seed"),
        (["task"], "must be None or a dict"),
        ({"task": [1.0, 2.0]}, "5 task-space coordinates"),
        ({"task": "abcde"}, "Task or its 5 task-space coordinates"),
        ({"task": Task((4.0, 0.5), (4.0, 0.0), 0.0)}, "overlap"),
        ({"task": Task((17.5, 0.0), (0.0, 0.0), 0.0)}, "outside the world"),
    ],
)
def test_malformed_reset_options_raise_clear_errors(options, message):
    env = MediatedInteractionEnv()
    with pytest.raises(ValueError, match=message):
        env.reset(options=options)


@pytest.mark.parametrize("action", [-1, NUM_ACTIONS, 2.5, "1", None])
def test_invalid_actions_are_rejected(action):
    env = make()
    with pytest.raises(ValueError, match=r"integer in \[0, 11\)"):
        env.step(action)


def test_step_before_reset_is_an_error():
    with pytest.raises(RuntimeError, match="reset"):
        MediatedInteractionEnv().step(PICK_O)


def test_a_closed_environment_refuses_to_step_or_reset():
    env = gymnasium.make(ENV_ID)
    env.reset(seed=0)
    env.step(PICK_O)
    env.close()
    for call in (lambda: env.step(PICK_O), lambda: env.reset(seed=0)):
        with pytest.raises(RuntimeError, match="^the environment is closed: make a new one"):
            call()
    gymnasium.make(ENV_ID).reset(seed=0)  # a new one works


@pytest.mark.skipif(importlib.util.find_spec("pygame") is not None, reason="pygame is installed here")
def test_human_rendering_without_pygame_is_refused_when_made_not_at_reset():
    with pytest.raises(ValueError, match="^render_mode='human' shows frames with pygame, which is not installed"):
        gymnasium.make(ENV_ID, render_mode="human")
    assert gymnasium.make(ENV_ID, render_mode="rgb_array_list").render_mode == "rgb_array_list"


@pytest.mark.parametrize("limit, message", [
    (-1, r"^max_episode_steps=-1 \(no time limit\) cannot hold: .*max_episode_steps=100 steps"),
    (500, "^max_episode_steps=500 exceeds the world's own limit, its config's max_episode_steps=100"),
])
def test_an_episode_limit_the_world_would_not_keep_is_refused_when_made(limit, message):
    with pytest.raises(ValueError, match=message):
        gymnasium.make(ENV_ID, max_episode_steps=limit)


@pytest.mark.parametrize("kwargs, steps", [({"max_episode_steps": 30}, 30), ({}, 100),
                                           ({"max_episode_steps": 150, "config": {"max_episode_steps": 150}}, 150)])
def test_an_episode_limit_the_world_keeps_ends_episodes_there(kwargs, steps):
    env = gymnasium.make(ENV_ID, **kwargs)
    env.reset(seed=0)
    for taken in range(1, 1000):
        _, _, terminated, truncated, _ = env.step(PICK_O)  # O is absorbing: nothing ever succeeds
        if terminated or truncated:
            break
    assert truncated and taken == steps


@pytest.mark.parametrize("task, message", [
    (Task("ab", (4.0, 3.0), 0.0), "target_position must be 2 numbers \\(x, y\\), got 'ab'"),
    (Task((12.0,), (4.0, 3.0), 0.0), "target_position must be 2 numbers \\(x, y\\), got \\(12.0,\\)"),
    (Task((12.0, 0.0, 1.0), (4.0, 3.0, 0.0), 0.0),
     "target_position must be 2 numbers.*; tool_position must be 2 numbers \\(x, y\\), got \\(4.0, 3.0, 0.0\\)"),
    (Task((12.0, 0.0), (4.0, 3.0), "a"), "tool_angle must be a number \\(radians\\), got 'a'"),
    (Task((12.0, True), (4.0, 3.0), 0.0), "target_position must be 2 numbers"),
])
def test_a_task_whose_fields_are_not_numbers_names_the_field(task, message):
    # Not a TypeError, an IndexError or an "overlap" measured on the wrong coordinates.
    for check in (task.validate, lambda: MediatedInteractionEnv().reset(options={"task": task})):
        with pytest.raises(ValueError, match=message) as caught:
            check()
        assert "\n" not in str(caught.value)
    assert HAND_BUILT.problems() == [] and Task(np.array([12.0, 0.0]), (4.0, 3.0), np.float64(0.0)).problems() == []
