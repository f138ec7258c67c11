"""The learning example (examples/learn_to_catch.py): its evolution strategy, a little of
it, against the real server; and what its fielder is allowed to see."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from fieldhouse.env import FIELDER_OBSERVATION
from fieldhouse.vector import FieldhouseVectorEnv

from .conftest import load_example

learn_to_catch = load_example("learn_to_catch")


def test_a_short_training_does_better_than_its_random_start_on_balls_it_never_saw(server):
    trained = learn_to_catch.train(
        server.url,
        server.admin_token,
        seed=1,
        generations=12,
        population=8,
        balls=3,
        log=lambda _: None,
    )
    assert len(trained.history) == 12
    # Balls from a seed training never drew from, for the start and the end alike.
    held_out = learn_to_catch.draw_launches(np.random.default_rng(2024), 8)
    venv = FieldhouseVectorEnv(
        2,
        server.url,
        learn_to_catch.scenario(held_out),
        admin_token=server.admin_token,
        autoreset_mode=AutoresetMode.DISABLED,
    )
    try:
        outcomes = learn_to_catch.play(venv, np.stack([trained.start, trained.weights]), held_out)
    finally:
        venv.close()
    start, end = outcomes.score()
    assert outcomes.caught.shape == (2, 8)
    assert not np.isnan(outcomes.miss_m).any(), "every ball was perceived in flight"
    assert end > start + 0.5, f"score {start:.2f} at the start, {end:.2f} after training"


def test_the_policy_sees_no_distance_and_no_position():
    # The same optics and velocity from two places at two distances: the same action.
    obs = np.zeros((2, len(FIELDER_OBSERVATION)), np.float32)
    i = {name: k for k, name in enumerate(FIELDER_OBSERVATION)}
    for row, (distance, x) in enumerate([(30.0, 50.0), (90.0, -20.0)]):
        obs[row, [i["ball_in_play"], i["tan_psi"], i["d_tan_psi_dt"], i["alpha"]]] = 1, 0.4, 0.3, 2
        obs[row, [i["d_alpha_dt"], i["t"], i["vx"], i["vz"]]] = 0.05, 1.0, 3.0, -1.0
        obs[row, [i["distance_m"], i["x"], i["z"]]] = distance, x, x
    weights = np.random.default_rng(0).normal(size=(2, 2, len(learn_to_catch.FEATURES)))
    weights[1] = weights[0]
    a = learn_to_catch.Policy(2).act(weights, obs)
    assert np.allclose(a[0], a[1]) and np.linalg.norm(a[0]) > 0
    # Before the reaction time, and between balls, it stands.
    obs[:, i["t"]] = 0.2
    assert not learn_to_catch.Policy(2).act(weights, obs).any()


def test_weights_saved_load_back_and_a_foreign_file_is_refused(tmp_path):
    weights = np.random.default_rng(1).normal(size=(2, len(learn_to_catch.FEATURES)))
    path = tmp_path / "weights.json"
    learn_to_catch.save_weights(path, weights)
    assert np.array_equal(learn_to_catch.load_weights(path), weights)
    path.write_text('{"toward": {"distance_m": 1.0}, "across": {}}')
    with pytest.raises(ValueError, match="distance_m"):
        learn_to_catch.load_weights(path)
