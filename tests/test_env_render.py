"""Rendering as in the paper's Figure 1, the GIF command, and the speed benchmark's report."""

import math

import numpy as np
import pytest
from PIL import Image

from mediated_transfer.bench import env_speed
from mediated_transfer.env import M2, MediatedInteractionEnv, Task, WorldConfig
from mediated_transfer.env import animate
from mediated_transfer.env.mediated_env import PICK_M2
from mediated_transfer.env.render import ACTIVE, TARGET, TOOL, WorldRenderer


def close(pixel, colour, tolerance=40):
    return bool(np.all(np.abs(pixel.astype(int) - np.array(colour)) <= tolerance))


def test_rgb_array_shows_target_tool_and_the_active_location():
    config = WorldConfig(action_noise=0.0)
    env = MediatedInteractionEnv("target", config, render_mode="rgb_array")
    env.reset(options={"task": Task((12.0, 0.0), (4.0, 3.0), 0.0)})
    env.step(PICK_M2)
    frame = env.render()
    assert frame.shape == (480, 480, 3) and frame.dtype == np.uint8
    to_pixel = WorldRenderer(config).to_pixel
    column, row = to_pixel(*env.picking_locations[M2])
    assert close(frame[row, column], ACTIVE)
    column, row = to_pixel(12.6, 0.0)  # inside the target disc, off its centre dot
    assert close(frame[row, column], TARGET)
    column, row = to_pixel(7.5, 3.0)  # middle of the handle
    assert close(frame[row, column], TOOL)


def test_render_without_mode_returns_nothing():
    env = MediatedInteractionEnv()
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


def test_animate_writes_a_gif_of_the_episode(tmp_path):
    out = tmp_path / "episode.gif"
    summary = animate.main(
        ["--scenario", "source", "--policy", "scripted", "--out", str(out), "--seed", "0",
         "--noise", "0"]
    )
    assert summary["is_success"]
    with Image.open(out) as gif:
        assert gif.n_frames == summary["steps"] + 1


def test_animate_shows_a_named_world(tmp_path):
    out = tmp_path / "tool_frame.gif"
    summary = animate.main(["--env", "tool_frame", "--out", str(out), "--seed", "1"])
    assert summary["is_success"] and out.exists()
    with pytest.raises(SystemExit, match="env=nope: no such option; allowed: default"):
        animate.main(["--env", "nope", "--out", str(tmp_path / "x.gif")])


def test_animate_rejects_an_unknown_policy(tmp_path):
    with pytest.raises(SystemExit):
        animate.main(["--policy", "clever", "--out", str(tmp_path / "x.gif")])


def test_record_episode_needs_rgb_array():
    with pytest.raises(ValueError, match="rgb_array"):
        animate.record_episode(MediatedInteractionEnv(), lambda observation: 0)


def test_env_speed_reports_speed_and_overhead(capsys):
    # A short learning run: its episodes replay bit for bit (checked inside) and are timed.
    result = env_speed.run(steps=400, rounds=2, learn_steps=1_000)
    for prefix in ("", "random_"):
        # The overhead is a difference of two timings: a busy machine can make it negative, so
        # the test asks for a measured number, and make bench for its size.
        assert result[f"{prefix}steps_per_second"] > 0 and math.isfinite(result[f"{prefix}overhead"])
        assert 0 < result[f"{prefix}physics_calls_per_step"] <= WorldConfig().substeps
    assert "overhead" in capsys.readouterr().out
