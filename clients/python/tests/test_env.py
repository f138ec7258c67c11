"""The environments against the real server: PettingZoo's and Gymnasium's own API
checks, and rewards and terminations that mean what the docs say."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

from fieldhouse.env import (
    FIELDER_OBSERVATION,
    FieldhouseGymEnv,
    FieldhouseParallelEnv,
    basketball_scenario,
    fly_ball_scenario,
)
from fieldhouse.errors import NotFound
from fieldhouse.messages import Optics, Rates

from .conftest import REPO


def load_example(name: str):
    path = REPO / "clients" / "python" / "examples" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_fly_ball_env_passes_pettingzoo_parallel_api_test(server):
    env = FieldhouseParallelEnv(
        server.url, fly_ball_scenario(fielders=2), admin_token=server.admin_token
    )
    try:
        parallel_api_test(env, num_cycles=400)
    finally:
        env.close()


def test_basketball_env_passes_pettingzoo_parallel_api_test(server):
    # A step is 0.25 s of play, paced by the server: a few cycles.
    env = FieldhouseParallelEnv(
        server.url,
        basketball_scenario(bots=("o1", "d1")),
        admin_token=server.admin_token,
        max_steps=8,
    )
    try:
        parallel_api_test(env, num_cycles=10)
        assert env.observation_space("o1").shape == (7 + 7 * 3,)
        assert env.action_space("d1").n == 13
    finally:
        env.close()


def test_single_fielder_passes_gymnasium_check_env(server):
    env = FieldhouseGymEnv(
        server.url, fly_ball_scenario(), admin_token=server.admin_token, max_steps=50
    )
    try:
        check_env(env, skip_render_check=True)
    finally:
        env.close()


def test_a_catch_is_rewarded_and_the_last_ball_terminates(server):
    """Chapman's fielder, driven through the environment from its observations, catches
    the default fly: reward 1 on one step, then the match ends (termination)."""
    chapman = load_example("chapman_bot")
    env = FieldhouseGymEnv(server.url, fly_ball_scenario(), admin_token=server.admin_token)
    fielder = chapman.Chapman()
    try:
        obs, _ = env.reset(seed=3)
        assert obs[FIELDER_OBSERVATION.index("ball_in_play")] == 0.0
        rewards, steps, terminated, truncated = [], 0, False, False
        while not (terminated or truncated):
            accel = fielder.accelerate(optics_of(obs)) or (0.0, 0.0)
            obs, reward, terminated, truncated, info = env.step(np.asarray(accel, np.float32) / 4.5)
            rewards.append(reward)
            steps += 1
        assert terminated and not truncated
        assert sum(rewards) == 1.0 and rewards.count(1.0) == 1
        assert 200 < steps < 600, steps
    finally:
        env.close()


def optics_of(obs: np.ndarray) -> Optics | None:
    """The optical variables of a fielder observation, as the perception gives them."""
    v = dict(zip(FIELDER_OBSERVATION, obs.astype(float), strict=True))
    if not v["ball_in_play"]:
        return None
    rates = Rates(v["d_tan_psi_dt"], v["d_alpha_dt"])
    return Optics(v["tan_psi"], v["alpha"], v["distance_m"], v["t"], rates)


def test_basketball_points_reward_offense_and_cost_defense(server):
    env = FieldhouseParallelEnv(
        server.url,
        basketball_scenario(bots=("o1", "d1"), possessions=1),
        admin_token=server.admin_token,
    )
    try:
        env.reset(seed=1)
        totals = {"o1": 0.0, "d1": 0.0}
        while env.agents:
            # o1 shoots whenever it can; d1 stands still.
            _, rewards, terms, truncs, infos = env.step({"o1": 1, "d1": 0})
            for agent, r in rewards.items():
                totals[agent] += r
        assert totals["o1"] == -totals["d1"]
        assert all(terms.values())
        match_id = env.match_id
        final = env.client.get_match(match_id)["score"]
        assert totals["o1"] == final["points"]
    finally:
        env.close()
    with pytest.raises(NotFound):  # close() deletes the match
        env.client.get_match(match_id)


def test_scenarios_without_the_right_bots_are_refused():
    with pytest.raises(ValueError, match="bot"):
        FieldhouseParallelEnv("http://127.0.0.1:1", {"sport": "baseball"})
    with pytest.raises(ValueError, match="FieldhouseParallelEnv"):
        FieldhouseGymEnv("http://127.0.0.1:1", fly_ball_scenario(fielders=2))
