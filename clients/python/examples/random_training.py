"""A training loop over the PettingZoo environment with a random policy: the skeleton an
RL learner plugs into (replace ``policy`` and feed ``transitions`` to it).

    FIELDHOUSE_ADMIN_TOKEN=... python random_training.py --server http://127.0.0.1:7878
    python random_training.py --server http://127.0.0.1:7878 --sport basketball --episodes 1

Each episode is a lock-step match on the server: fly balls for two bot fielders (reward 1
per catch), or the 2-v-1 basketball with the environment playing ``o1`` and ``d1``
(reward: the offense's points, negated for the defender).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fieldhouse.env import FieldhouseParallelEnv, basketball_scenario, fly_ball_scenario

LAUNCHES = [
    {"time_s": 0.5, "speed_m_s": 36.0, "elevation_deg": 40.0, "azimuth_deg": 40.0},
    {"time_s": 0.0, "speed_m_s": 32.0, "elevation_deg": 55.0, "azimuth_deg": 52.0},
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--server", help="the server's URL (default: $FIELDHOUSE_URL, else http://127.0.0.1:7878)"
    )
    parser.add_argument("--sport", choices=["baseball", "basketball"], default="baseball")
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    if args.sport == "baseball":
        scenario = fly_ball_scenario(fielders=2, launches=LAUNCHES)
    else:
        scenario = basketball_scenario(bots=("o1", "d1"), possessions=2)
    env = FieldhouseParallelEnv(args.server, scenario)
    rng = np.random.default_rng(args.seed)
    for agent in env.possible_agents:
        env.action_space(agent).seed(int(rng.integers(1 << 31)))

    def policy(agent: str, observation: np.ndarray):
        return env.action_space(agent).sample()

    try:
        for episode in range(args.episodes):
            observations, _ = env.reset(seed=args.seed + episode)
            returns = dict.fromkeys(env.agents, 0.0)
            transitions = 0
            start = time.perf_counter()
            while env.agents:
                actions = {a: policy(a, observations[a]) for a in env.agents}
                observations, rewards, terminations, truncations, _ = env.step(actions)
                for agent, reward in rewards.items():
                    returns[agent] += reward
                transitions += 1
            elapsed = time.perf_counter() - start
            print(
                f"episode {episode}: {transitions} steps in {elapsed:.2f} s "
                f"({transitions / elapsed:.0f} steps/s), returns {returns}"
            )
    finally:
        env.close()


if __name__ == "__main__":
    main()
