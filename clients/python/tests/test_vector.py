"""FieldhouseVectorEnv: several matches stepped on one event loop, checked against the
single environment it batches (an independent path through the same server)."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from fieldhouse.env import FieldhouseGymEnv, fly_ball_scenario
from fieldhouse.vector import FieldhouseVectorEnv

# Two balls: the first one lands or is caught, the second ends the match.
LAUNCHES = [
    {"time_s": 0.5, "speed_m_s": 32.0, "elevation_deg": 40.0, "azimuth_deg": 45.0},
    {"time_s": 0.0, "speed_m_s": 30.0, "elevation_deg": 45.0, "azimuth_deg": 40.0},
]


def test_each_environment_of_the_vector_steps_as_a_single_environment_would(server):
    scenario = fly_ball_scenario(launches=LAUNCHES)
    rng = np.random.default_rng(0)
    actions = [rng.uniform(-1, 1, (2, 2)).astype(np.float32) for _ in range(150)]
    vector = FieldhouseVectorEnv(2, server.url, scenario, admin_token=server.admin_token)
    try:
        observations, _ = vector.reset(seed=7)
        batched = [observations]
        for a in actions:
            observations, rewards, terminations, truncations, _ = vector.step(a)
            assert observations.shape == (2, 13) and rewards.shape == (2,)
            assert vector.observation_space.contains(observations)
            batched.append(observations)
    finally:
        vector.close()
    # Environment i was seeded 7 + i: alone, with the same actions, it goes the same way.
    for i in range(2):
        alone = FieldhouseGymEnv(server.url, scenario, admin_token=server.admin_token)
        try:
            observation, _ = alone.reset(seed=7 + i)
            assert np.array_equal(observation, batched[0][i])
            for k, a in enumerate(actions):
                observation, *_ = alone.step(a[i])
                assert np.array_equal(observation, batched[k + 1][i]), f"env {i}, step {k}"
        finally:
            alone.close()


def test_an_ended_episode_is_reset_on_the_next_step_and_close_ends_every_match(server):
    client = server.client()
    before = {m["id"] for m in client.list_matches()}
    one_ball = fly_ball_scenario(launches=LAUNCHES[:1])
    vector = FieldhouseVectorEnv(2, server.url, one_ball, admin_token=server.admin_token)
    try:
        vector.reset(seed=3)
        ids = [env.match_id for env in vector.envs]
        stand = np.zeros((2, 2), np.float32)
        for _ in range(2000):
            _, rewards, terminations, truncations, _ = vector.step(stand)
            if terminations.any():
                break
        assert terminations.all(), "both matches play the same single ball to its end"
        # Next step: a new episode (a new match) for each, reward 0.
        observations, rewards, terminations, truncations, _ = vector.step(stand)
        assert not terminations.any() and not truncations.any()
        assert rewards.tolist() == [0.0, 0.0]
        assert [env.match_id for env in vector.envs] != ids
        with pytest.raises(ValueError, match="3 actions for 2 environments"):
            vector.step(np.zeros((3, 2), np.float32))
    finally:
        vector.close()
    assert {m["id"] for m in client.list_matches() if m["status"] == "running"} <= before


def test_without_autoreset_an_ended_episode_waits_for_its_reset_and_options_pick_the_balls(
    server,
):
    # Constructed with two balls; each episode is given one through reset's options.
    two_balls = fly_ball_scenario(launches=LAUNCHES)
    vector = FieldhouseVectorEnv(
        2,
        server.url,
        two_balls,
        admin_token=server.admin_token,
        autoreset_mode=AutoresetMode.DISABLED,
    )
    stand = np.zeros((2, 2), np.float32)
    try:
        assert vector.metadata["autoreset_mode"] == AutoresetMode.DISABLED
        vector.reset(seed=3, options={"scenario_options": {"launches": LAUNCHES[:1]}})
        ids = [env.match_id for env in vector.envs]
        steps = 0
        while steps < 2000:
            steps += 1
            observations, _, terminations, _, _ = vector.step(stand)
            if terminations.all():
                break
        # One ball of about 4 s (240 ticks) after half a second: the second ball (the
        # scenario's) would have taken as long again.
        assert steps < 400, f"{steps} steps: the episode played the scenario's two balls"
        # Ended episodes stay ended: the same observation, no reward, no new match.
        again, rewards, terminations, truncations, _ = vector.step(stand)
        assert np.array_equal(again, observations) and rewards.tolist() == [0.0, 0.0]
        assert terminations.all() and not truncations.any()
        assert [env.match_id for env in vector.envs] == ids
        # A masked reset starts environment 0 alone.
        mask = np.array([True, False])
        observations, _ = vector.reset(options={"reset_mask": mask})
        assert vector.envs[0].match_id != ids[0] and vector.envs[1].match_id == ids[1]
        assert np.array_equal(observations[1], again[1])
        _, _, terminations, _, _ = vector.step(stand)
        assert terminations.tolist() == [False, True]
        with pytest.raises(ValueError, match="reset_mask"):
            vector.reset(options={"reset_mask": np.array([1, 0])})
    finally:
        vector.close()
    with pytest.raises(ValueError, match="NEXT_STEP .* or DISABLED"):
        FieldhouseVectorEnv(1, server.url, two_balls, autoreset_mode=AutoresetMode.SAME_STEP)
