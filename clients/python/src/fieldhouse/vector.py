"""Several single-agent environments stepped together in one process:
:class:`FieldhouseVectorEnv`, a Gymnasium ``VectorEnv``.

``gymnasium.vector.AsyncVectorEnv`` gives each environment a process of its own and pickles
every action and observation through a pipe. On a small machine that costs more than it
saves: one fieldhouse environment already keeps about a core busy between the client and
the server, and four in an ``AsyncVectorEnv`` stepped at 0.82 times one environment's rate
on two cores (BENCHMARKS.md, "Python clients"). Here the environments share one event
loop: a step sends every environment's command, then waits for all their perceptions
together, so the server plays the matches while the client reads what has come back,
and nothing is pickled.

Autoreset is Gymnasium's default, *next step*: the step after an environment's episode
ends resets it (a new match) and returns its first observation, with reward 0. With
``autoreset_mode=AutoresetMode.DISABLED`` an environment whose episode ended waits for
``reset(options={"reset_mask": mask})`` (or a plain ``reset()``): until then each step
leaves it alone and repeats its last observation, with reward 0 and the flags it ended
with. That suits an evaluator stepping several episodes of unequal length to their
ends (a population of policies, one per environment), where an autoreset would start
matches nobody wants.
"""

from __future__ import annotations

import asyncio
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .env import FieldhouseParallelEnv


class FieldhouseVectorEnv(VectorEnv):
    """``num_envs`` copies of the one-agent ``scenario`` on the server at ``url``, each
    its own match. The keywords are :class:`~fieldhouse.env.FieldhouseParallelEnv`'s."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int,
        url: str | None = None,
        scenario: dict | None = None,
        *,
        autoreset_mode: AutoresetMode = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ):
        if num_envs < 1:
            raise ValueError(f"num_envs {num_envs}: at least one environment")
        if autoreset_mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.DISABLED):
            raise ValueError(
                f"autoreset_mode {autoreset_mode}: NEXT_STEP (the default) or DISABLED"
            )
        self.autoreset_mode = autoreset_mode
        self.metadata = {**self.metadata, "autoreset_mode": autoreset_mode}
        self._loop = asyncio.new_event_loop()
        self.envs = [
            FieldhouseParallelEnv(url, scenario, loop=self._loop, **kwargs) for _ in range(num_envs)
        ]
        agents = self.envs[0].possible_agents
        if len(agents) != 1:
            raise ValueError(
                f"a vector environment steps one agent per match; the scenario has bots {agents}"
            )
        self.agent = agents[0]
        self.num_envs = num_envs
        self.single_observation_space = self.envs[0].observation_space(self.agent)
        self.single_action_space = self.envs[0].action_space(self.agent)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        # Each environment's latest observation (repeated, without autoreset, while its
        # episode is over) and whether its episode ended: terminated, truncated.
        space = self.single_observation_space
        self._observations = np.zeros((num_envs, *space.shape), dtype=space.dtype)
        self._ended = np.zeros((2, num_envs), dtype=bool)

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Resets every environment, or those of ``options["reset_mask"]`` (a bool array):
        with ``seed`` an int, environment i gets ``seed + i`` (as Gymnasium's vector
        environments do); a list gives each its own. The other options go to each
        environment's reset (``scenario_options``: :meth:`FieldhouseParallelEnv.reset`)."""
        super().reset(seed=seed)
        options = dict(options or {})
        mask = np.asarray(options.pop("reset_mask", np.ones(self.num_envs, dtype=bool)))
        if mask.shape != (self.num_envs,) or mask.dtype != np.bool_:
            raise ValueError(
                f"options['reset_mask'] must be a bool array of shape ({self.num_envs},), "
                f"got {mask!r}"
            )
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
        for i in np.flatnonzero(mask):
            self._observations[i] = self._reset_one(self.envs[i], seeds[i], options or None)
        self._ended[:, mask] = False
        return self._observations.copy(), {}

    def step(self, actions):
        n = self.num_envs
        if len(actions) != n:
            raise ValueError(f"{len(actions)} actions for {n} environments")
        # Every action checked first: a refused step sends nothing. An environment whose
        # episode ended is reset (next step) or left alone (disabled), not stepped.
        ended = self._ended.any(axis=0)
        playing = {
            i: env._commands({self.agent: actions[i]})
            for i, env in enumerate(self.envs)
            if not ended[i]
        }
        played = self._loop.run_until_complete(self._play_all(playing))
        results = dict(zip(playing, played, strict=True))
        rewards = np.zeros(n, dtype=np.float64)
        for i, env in enumerate(self.envs):
            if i not in results:
                if self.autoreset_mode == AutoresetMode.NEXT_STEP:
                    # The episode ended on the step before: this step starts the next.
                    self._observations[i] = self._reset_one(env, None, None)
                    self._ended[:, i] = False
                continue  # DISABLED: left alone until reset
            obs, reward, term, trunc, _ = env._finish(*results[i])
            self._observations[i] = obs[self.agent]
            rewards[i] = reward[self.agent]
            self._ended[:, i] = term[self.agent], trunc[self.agent]
        terminations, truncations = self._ended.copy()
        return self._observations.copy(), rewards, terminations, truncations, {}

    def close_extras(self, **kwargs: Any) -> None:
        try:
            for env in self.envs:
                env.close()
        finally:
            if not self._loop.is_closed():
                self._loop.close()

    async def _play_all(self, playing: dict[int, dict[str, str]]) -> list:
        """Every playing environment's step at once (gathered inside the loop: a gather
        made outside it would belong to another)."""
        return await asyncio.gather(*(self.envs[i]._play(c) for i, c in playing.items()))

    def _reset_one(self, env: FieldhouseParallelEnv, seed: int | None, options: dict | None):
        observations, _ = env.reset(seed=seed, options=options)
        return observations[self.agent]
