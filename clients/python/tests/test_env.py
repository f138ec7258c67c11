"""The environments against the real server: PettingZoo's and Gymnasium's own API
checks, and rewards and terminations that mean what the docs say."""

from __future__ import annotations

import math
import re
import urllib.request
import uuid
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

from fieldhouse.env import (
    COURT_OBSERVATION,
    DEFAULT_LAUNCH,
    FIELDER_OBSERVATION,
    PLAYER_OBSERVATION,
    FieldhouseGymEnv,
    FieldhouseParallelEnv,
    basketball_scenario,
    fielder_observation_space,
    fly_ball_scenario,
)
from fieldhouse.errors import BadScenario, FieldhouseError, NotFound
from fieldhouse.messages import Optics, Rates

from .conftest import load_example


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
            # Chapman asks for any acceleration; the action space's is at most 1 a side.
            action = np.clip(np.asarray(accel) / 4.5, -1.0, 1.0)
            obs, reward, terminated, truncated, info = env.step(action)
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


# --- what an RL user expects of an environment ---------------------------------------


def test_registered_ids_make_environments_from_the_environment_variables(server, monkeypatch):
    """``gymnasium.make`` finds both ids once fieldhouse.env is imported (or named in the
    id), and the server and token come from FIELDHOUSE_URL and FIELDHOUSE_ADMIN_TOKEN."""
    monkeypatch.setenv("FIELDHOUSE_URL", server.url)
    monkeypatch.setenv("FIELDHOUSE_ADMIN_TOKEN", server.admin_token)
    env = gymnasium.make("fieldhouse/FlyBall-v0")
    try:
        assert env.spec.max_episode_steps == 1250
        assert env.unwrapped.parallel.client.url == server.url
        obs, _ = env.reset(seed=1)
        assert env.observation_space.contains(obs)
        obs, *_ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs)
    finally:
        env.close()
    monkeypatch.delenv("FIELDHOUSE_URL")
    env = gymnasium.make(
        "fieldhouse.env:fieldhouse/Basketball-v0", url=server.url, agent="d1", possessions=1
    )
    try:
        assert env.spec.max_episode_steps == 200 and env.spec.nondeterministic
        assert env.unwrapped.agent == "d1" and env.action_space == spaces.Discrete(13)
        obs, _ = env.reset(seed=1)
        assert obs.shape == (7 + 7 * 3,)
        env.step(0)
    finally:
        env.close()


def test_observation_spaces_are_bounded_where_the_physics_bounds_them():
    fly = FieldhouseGymEnv("http://127.0.0.1:1", fly_ball_scenario()).observation_space
    bounds = dict(zip(FIELDER_OBSERVATION, zip(fly.low, fly.high, strict=True), strict=True))
    unbounded = {"tan_psi", "d_tan_psi_dt"}  # a ball over the eye: distance near 0
    for name, (low, high) in bounds.items():
        assert np.isfinite([low, high]).all() == (name not in unbounded), name
    assert bounds["ball_in_play"] == (0.0, 1.0)
    assert bounds["alpha"] == (np.float32(-math.pi), np.float32(math.pi))
    assert bounds["vx"] == (-8.5, 8.5)  # a human body's top speed
    assert 80.0 <= bounds["home_x"][1] < 80.01  # fly_ball_scenario's fielder, 80 m out
    assert bounds["t"][1] == pytest.approx(20.0, abs=0.02)  # the longest flight
    quick = fly_ball_scenario()
    quick["agents"][0]["limits"] = {"max_speed_m_s": 12.0, "max_accel_m_s2": 6.0}
    assert fielder_observation_space(quick).high[FIELDER_OBSERVATION.index("vz")] == 12.0

    court = FieldhouseParallelEnv("http://127.0.0.1:1", basketball_scenario()).observation_space(
        "o1"
    )
    assert np.isfinite(court.low).all() and np.isfinite(court.high).all()
    assert court.high[COURT_OBSERVATION.index("shot_clock_s")] == 24.0
    x = len(COURT_OBSERVATION) + PLAYER_OBSERVATION.index("x")
    assert (court.low[x], court.high[x]) == (-1.0, 15.0)  # the half court and its run-off


def assert_in_space(space, obs, recorded):
    assert space.contains(obs), obs
    # The environment clips what leaves its space, and warns: nothing here may.
    assert not [w for w in recorded if "outside its space" in str(w.message)]


def test_observations_over_real_episodes_stay_in_their_spaces(server):
    """A fielder running every way it can, and basketball bots acting at random, over
    whole episodes: every observation is in its space without clipping."""
    rng = np.random.default_rng(5)
    env = FieldhouseGymEnv(server.url, fly_ball_scenario(), admin_token=server.admin_token)
    try:
        with warnings.catch_warnings(record=True) as recorded:
            warnings.simplefilter("always")
            obs, _ = env.reset(seed=5)
            assert_in_space(env.observation_space, obs, recorded)
            done = False
            while not done:
                obs, _, terminated, truncated, _ = env.step(rng.choice([-1.0, 1.0], 2))
                assert_in_space(env.observation_space, obs, recorded)
                done = terminated or truncated
    finally:
        env.close()
    env = FieldhouseParallelEnv(
        server.url, basketball_scenario(possessions=2), admin_token=server.admin_token
    )
    try:
        with warnings.catch_warnings(record=True) as recorded:
            warnings.simplefilter("always")
            observations, _ = env.reset(seed=5)
            while env.agents:
                for agent, obs in observations.items():
                    assert_in_space(env.observation_space(agent), obs, recorded)
                actions = {a: int(rng.integers(env.action_space(a).n)) for a in env.agents}
                observations, *_ = env.step(actions)
    finally:
        env.close()


def test_an_action_outside_its_space_is_refused_naming_agent_action_and_space(server):
    env = FieldhouseGymEnv(server.url, fly_ball_scenario(), admin_token=server.admin_token)
    try:
        env.reset(seed=2)
        space = re.escape("Box(-1.0, 1.0, (2,), float32)")
        for action in (
            np.zeros(3),
            [0.5],
            np.zeros((2, 1)),
            np.array([np.nan, 0.0]),
            np.array([1.5, 0.0]),
            np.array(["a", "b"]),
            [[1.0], 2.0],
            None,
        ):
            with pytest.raises(ValueError, match=rf"agent 'f0'.*action .*{space}"):
                env.step(action)
        # Refused steps sent nothing: the episode goes on, and any real numbers in range
        # are an action, float64 and lists included.
        tick = env.parallel._perceptions["f0"]["tick"]
        _, _, _, _, info = env.step(np.array([1.0, -1.0]))
        assert info["tick"] == tick + 1
        env.step([0, 0.25])
    finally:
        env.close()
    env = FieldhouseParallelEnv(
        server.url, basketball_scenario(bots=("o1",), possessions=1), admin_token=server.admin_token
    )
    try:
        env.reset(seed=2)
        for action in (13, -1, 1.0, "1", np.array([1, 2])):
            with pytest.raises(ValueError, match=r"agent 'o1'.*Discrete\(13\)"):
                env.step({"o1": action})
        env.step({"o1": np.int64(0)})
    finally:
        env.close()


def test_render_names_the_spectator_page(server):
    env = FieldhouseGymEnv(server.url, fly_ball_scenario(), admin_token=server.admin_token)
    try:
        assert env.spectator_url is None
        env.reset(seed=1)
        live = f"{server.url}/#/matches/{env.parallel.match_id}"
        assert env.spectator_url == live
        with pytest.warns(UserWarning, match=re.escape(live)):
            assert env.render() is None  # Gymnasium's convention without a render mode
        # The page is there, and serves the route's script.
        with urllib.request.urlopen(server.url + "/web/app.js") as page:
            assert b"#/matches/" in page.read()
    finally:
        env.close()
    with pytest.raises(ValueError, match=re.escape(f"{server.url}/#/matches/")):
        FieldhouseGymEnv(server.url, fly_ball_scenario(), render_mode="human")
    pz = FieldhouseParallelEnv(server.url, fly_ball_scenario())
    with pytest.warns(UserWarning, match="spectator page"):
        assert pz.render() is None
    pz.close()


def fly_ball_trajectory(server, seed: int | None) -> tuple[list, int]:
    """The first ball's flight, the fielder driven by actions drawn from the
    environment's np_random (after a reset with ``seed``), and the match seed of a reset
    without one after it. A second ball follows, so the first one's end is a perception
    like any other, not the match's end."""
    launches = [DEFAULT_LAUNCH, {**DEFAULT_LAUNCH, "time_s": 0.0}]
    env = FieldhouseGymEnv(
        server.url, fly_ball_scenario(launches=launches), admin_token=server.admin_token
    )
    try:
        obs, _ = env.reset(seed=seed)
        ball_in_play = FIELDER_OBSERVATION.index("ball_in_play")
        trajectory = []
        while not (trajectory and obs[ball_in_play] == 0.0):  # until the first ball is dead
            # Before the launch the fielder stands (how many ticks that is depends on when
            # its bot was seated); the launch puts it back home at rest.
            in_play = obs[ball_in_play] == 1.0
            action = env.np_random.uniform(-1.0, 1.0, 2) if in_play else np.zeros(2)
            obs, reward, terminated, truncated, _ = env.step(action)
            assert not (terminated or truncated)
            if in_play:
                trajectory.append((obs.tolist(), reward))
        env.reset()
        next_seed = env.parallel.client.get_match(env.parallel.match_id)["scenario"]["seed"]
        return trajectory, next_seed
    finally:
        env.close()


def test_the_same_seed_and_actions_give_the_same_trajectory(server):
    first, next_seed = fly_ball_trajectory(server, 7)
    again, next_again = fly_ball_trajectory(server, 7)
    assert len(first) > 100 and first == again
    # reset() without a seed goes on from the seeded sequence: the same match next.
    assert next_seed == next_again


def test_reset_seeds_the_gymnasium_np_random(server):
    env = FieldhouseGymEnv(server.url, fly_ball_scenario(), admin_token=server.admin_token)
    try:
        env.reset(seed=11)
        drawn = env.np_random.integers(1 << 30, size=4).tolist()
        assert env.parallel.client.get_match(env.parallel.match_id)["scenario"]["seed"] == 11
        env.reset(seed=11)
        assert env.np_random.integers(1 << 30, size=4).tolist() == drawn
    finally:
        env.close()


def test_without_a_server_reset_says_how_to_start_one(closed_port_url):
    env = FieldhouseGymEnv(closed_port_url, fly_ball_scenario(), admin_token="t" * 16)
    try:
        with pytest.raises(FieldhouseError, match="fieldhouse serve") as e:
            env.reset()
        assert e.value.code == "unreachable" and closed_port_url in str(e.value)
    finally:
        env.close()


def test_episodes_are_not_recorded_unless_asked(server):
    env = FieldhouseGymEnv(server.url, fly_ball_scenario(), admin_token=server.admin_token)
    try:
        env.reset(seed=1)
        match = env.parallel.client.get_match(env.parallel.match_id)
        assert match["replay"] is None and match["name"] == "fieldhouse env"
    finally:
        env.close()
    env = FieldhouseParallelEnv(
        server.url,
        fly_ball_scenario(),
        admin_token=server.admin_token,
        record=True,
        name="recorded on purpose",
    )
    try:
        env.reset(seed=1)
        match = env.client.get_match(env.match_id)
        assert match["replay"] is not None and match["name"] == "recorded on purpose"
    finally:
        env.close()


def test_close_deletes_the_match_through_gymnasium_wrappers(server):
    env = gymnasium.make("fieldhouse/FlyBall-v0", url=server.url, admin_token=server.admin_token)
    env.reset(seed=1)
    match_id = env.unwrapped.parallel.match_id
    client = env.unwrapped.parallel.client
    assert client.get_match(match_id)["status"] == "running"
    env.close()
    with pytest.raises(NotFound):
        client.get_match(match_id)


def test_a_reset_that_fails_leaves_no_match_behind(server):
    """A match over before its bot is seated (one tick long): the reset raises, and the
    match it created is deleted, not left to the server."""
    name = f"ends at once {uuid.uuid4().hex}"
    scenario = fly_ball_scenario()
    scenario.update(tick_hz=1000.0, duration_s=0.001)
    env = FieldhouseGymEnv(server.url, scenario, admin_token=server.admin_token, name=name)
    try:
        with pytest.raises(FieldhouseError):
            env.reset(seed=1)
        assert env.parallel.match_id is None
        assert not [m for m in env.parallel.client.list_matches() if m.get("name") == name]
    finally:
        env.close()


def test_an_observation_past_its_bounds_is_clipped_into_its_space_with_a_warning():
    """Were the server ever to leave the bounds (a fielder 900 m out), the observation
    still keeps the space's promise, and the warning names the field."""
    env = FieldhouseParallelEnv("http://127.0.0.1:1", fly_ball_scenario())
    body = {"position": [900.0, 0.0], "velocity": [0.0, 0.0], "home": [56.569, 56.569]}
    env._perceptions["f0"] = {"tick": 1, "perception": {"self": body, "optics": None}}
    with pytest.warns(RuntimeWarning, match=r"agent 'f0'.* at x: clipped"):
        obs = env._observe("f0")
    assert env.observation_space("f0").contains(obs)
    env.close()


def test_scenario_options_the_server_refuses_are_a_bad_scenario_naming_the_field(server):
    env = FieldhouseGymEnv(server.url, fly_ball_scenario(), admin_token=server.admin_token)
    steep = {"time_s": 0.5, "speed_m_s": 30.0, "elevation_deg": 95.0, "azimuth_deg": 45.0}
    try:
        with pytest.raises(BadScenario, match=r"launches\[0\]\.elevation_deg"):
            env.reset(seed=1, options={"scenario_options": {"launches": [steep]}})
        assert env.parallel.match_id is None
        # The environment's own scenario is untouched: the next episode plays it. An
        # option that is not a scenario's is not used, and said so.
        with pytest.warns(UserWarning, match=r"\['launches'\] are not used"):
            observation, _ = env.reset(seed=1, options={"launches": [steep]})
        assert env.observation_space.contains(observation)
    finally:
        env.close()
