"""A PettingZoo ``ParallelEnv`` over a lock-step match, and a single-agent Gymnasium
wrapper (needs the ``env`` extra: ``pip install './clients/python[env]'``).

**Episodes.** :meth:`FieldhouseParallelEnv.reset` creates a ``lockstep`` match on the
server from the scenario (sport, line-up: the agents with ``"bot": true`` are the
environment's agents; the others play their built-in strategies) with the match seed
``seed`` (else the next of a sequence the last seed given started), seats a bot on each
agent, and returns their first perceptions. :meth:`~FieldhouseParallelEnv.step` sends one
command per agent for the tick it perceived; the server plays on once every bot has
answered (PROTOCOL.md, "Modes") and the next perceptions are the observations. The match's
``end`` (the last scripted ball dead, ``options.possessions`` played, ``duration_s``) ends
the episode for every agent (*termination*); ``max_steps`` cuts it short (*truncation*).
:meth:`~FieldhouseParallelEnv.close` (and the next ``reset``) deletes the match.

Until the bots are seated the match ticks in real time, its agents on their built-in
brains: :func:`fly_ball_scenario` therefore hits its first ball half a second in, and a
basketball episode may start a few ticks into its first possession.

**Fielders** (baseball, cricket) perceive every tick, so a step is one tick (1/60 s).

* Observation: ``Box(13,)`` float32, :data:`FIELDER_OBSERVATION` in order:
  ``ball_in_play`` (0 or 1), then the optical variables ``tan_psi``, ``d_tan_psi_dt``,
  ``alpha``, ``d_alpha_dt``, ``distance_m``, ``t`` (0 between balls; rates 0 on a ball's
  first tick), then the fielder's own ``x``, ``z``, ``vx``, ``vz``, ``home_x``, ``home_z``
  (m, m/s). These are exactly the perception's fields (PROTOCOL.md, "`perception`").
* Action: ``Box(-1, 1, (2,))``: an acceleration ``[ax, az]`` in units of the body's
  ``max_accel_m_s2``, sent as ``accelerate`` (the server clips its length to the body).
* Reward: 1 on the step whose tick the agent caught a ball (its perception's ``caught``
  count rose), else 0.

**Basketball** players perceive every 15 ticks (0.25 s of play); the server plays the 14
ticks between at once (PROTOCOL.md, "Modes"), so a step takes as long as the agents take to
answer, not 0.25 s.

* Observation: ``Box(7 + 7·P,)`` float32 for P players, :data:`COURT_OBSERVATION` then
  :data:`PLAYER_OBSERVATION` for each player in the hello's order (offense first):
  ``shot_clock_s``, the ball's ``x``, ``y``, ``z`` and state one-hot (``held``, ``pass``,
  ``shot``); per player ``x``, ``z``, ``cos heading``, ``sin heading``, ``has_ball``,
  ``is_self``, ``offense``.
* Action: ``Discrete(10 + P)``: 0 ``stand``, 1 ``shoot``, 2 to 9 ``move_to`` a point 2 m
  away at bearing ``k·45°`` (k = action − 2, clamped to the court), 10 + i ``pass`` to
  player i. An action the player cannot take (a shot without the ball, a pass to a
  defender) is refused by the server and ignored; its message is in the info's
  ``rejected``.
* Reward: the offense's points scored during the step, for each offensive player; their
  negative for each defender.

A fielder's rewards come from its own perceptions (``caught``), so a fly-ball environment
holds only its bots' sockets. Basketball's come from the match's frames, read on a
spectator socket the environment opens beside the bots (a player's perception carries no
score); the environment sets ``frame_hz`` to ``tick_hz`` so that every tick's events arrive
with the tick, and each step reads the frames up to its tick (a frame the server's
fan-out skips for a lagging spectator costs nothing: a later frame carries the score).
"""

from __future__ import annotations

import asyncio
import copy
import math
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from .bot import Socket
from .errors import ConnectionClosed, FieldhouseError, NotFound
from .rest import Client

FIELDER_OBSERVATION = (
    "ball_in_play",
    "tan_psi",
    "d_tan_psi_dt",
    "alpha",
    "d_alpha_dt",
    "distance_m",
    "t",
    "x",
    "z",
    "vx",
    "vz",
    "home_x",
    "home_z",
)
COURT_OBSERVATION = ("shot_clock_s", "ball_x", "ball_y", "ball_z", "held", "pass", "shot")
PLAYER_OBSERVATION = ("x", "z", "cos_heading", "sin_heading", "has_ball", "is_self", "offense")
BALL_STATES = ("held", "pass", "shot")
FLY_SPORTS = ("baseball", "cricket")
MOVE_M = 2.0
COURT = {"length_m": 14.0, "width_m": 15.0}

# The first ball of fly_ball_scenario: a fly to centre field, hit once the bots are seated.
DEFAULT_LAUNCH = {"time_s": 0.5, "speed_m_s": 36.0, "elevation_deg": 40.0, "azimuth_deg": 45.0}


def fly_ball_scenario(
    fielders: int = 1, launches: list[dict] | None = None, sport: str = "baseball"
) -> dict:
    """A lock-step fly-ball scenario with ``fielders`` bot fielders (ids ``f0``, ``f1``,
    ..., 80 m out around centre field, 20 degrees apart) and scripted ``launches``
    (default: one fly to centre field); the episode ends when the last ball is dead."""
    return {
        "sport": sport,
        "agents": [
            {"id": f"f{i}", "bot": True, "position": _outfield_home(i, fielders)}
            for i in range(fielders)
        ],
        "options": {"pause_s": 0.5, "launches": launches or [DEFAULT_LAUNCH]},
    }


def _outfield_home(i: int, n: int) -> list[float]:
    """Fielder i of n, 80 m out, 20 degrees apart around centre field (azimuth 45)."""
    azimuth = math.radians(45.0 + 20.0 * (i - (n - 1) / 2))
    return [round(80.0 * math.cos(azimuth), 3), round(80.0 * math.sin(azimuth), 3)]


def basketball_scenario(bots: tuple[str, ...] = ("o1", "d1"), possessions: int = 2) -> dict:
    """The paper's 2-v-1 (``o1``, ``o2`` against ``d1``) with ``bots`` played by the
    environment and the others by their built-in brains, for ``possessions``."""
    line_up = [
        ("o1", "offense", "costmap"),
        ("o2", "offense", "costmap"),
        ("d1", "defense", "defense"),
    ]
    return {
        "sport": "basketball",
        "agents": [
            {"id": i, "team": team, "strategy": strategy, "bot": i in bots}
            for i, team, strategy in line_up
        ],
        "options": {"possessions": possessions},
    }


class FieldhouseParallelEnv(ParallelEnv):
    """The bot agents of ``scenario`` on the server at ``url`` (see the module's doc).

    ``admin_token`` (default ``FIELDHOUSE_ADMIN_TOKEN``) creates and deletes the matches.
    ``max_steps`` truncates an episode; ``deadline_ms`` is how long the server waits for
    a command before playing a tick without it.
    """

    metadata = {"name": "fieldhouse_v0", "render_modes": []}

    def __init__(
        self,
        url: str,
        scenario: dict,
        *,
        admin_token: str | None = None,
        max_steps: int | None = None,
        deadline_ms: int = 5000,
    ):
        agents = scenario.get("agents")
        if not agents or not any(a.get("bot") for a in agents):
            raise ValueError('the scenario needs agents, at least one with "bot": true')
        self.client = Client(url, admin_token)
        self.scenario = copy.deepcopy(scenario)
        self.scenario.update(mode="lockstep", lockstep_deadline_ms=deadline_ms)
        self.scenario["frame_hz"] = self.scenario.get("tick_hz", 60.0)
        self.sport = self.scenario["sport"]
        self.fly = self.sport in FLY_SPORTS
        self.max_steps = max_steps
        self.possible_agents = [a["id"] for a in agents if a.get("bot")]
        self.agents: list[str] = []
        if self.fly:
            obs = spaces.Box(-np.inf, np.inf, (len(FIELDER_OBSERVATION),), np.float32)
            act: spaces.Space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        else:
            players = len(agents)
            size = len(COURT_OBSERVATION) + len(PLAYER_OBSERVATION) * players
            obs = spaces.Box(-np.inf, np.inf, (size,), np.float32)
            act = spaces.Discrete(10 + players)
        self.observation_spaces = {a: obs for a in self.possible_agents}
        self.action_spaces = {a: act for a in self.possible_agents}
        self.match_id: str | None = None
        self.steps = 0
        self._seeds = np.random.default_rng()
        self._loop = asyncio.new_event_loop()
        self._bots: dict[str, Socket] = {}
        self._spectator: Socket | None = None
        self._perceptions: dict[str, dict] = {}
        self._players: list[str] = []  # basketball: every player, in the hello's order
        self._offense: set[str] = set()
        self._points = 0

    def observation_space(self, agent: str) -> spaces.Space:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self.action_spaces[agent]

    # --- episodes --------------------------------------------------------------------

    def reset(self, seed: int | None = None, options: dict | None = None):
        self._end_match()
        # The match's seed: ``seed``, or else the next draw of a generator that the last
        # seed given started, so that episodes differ and a seeded run repeats.
        if seed is not None:
            self._seeds = np.random.default_rng(seed)
        scenario = copy.deepcopy(self.scenario)
        scenario["seed"] = int(seed) if seed is not None else int(self._seeds.integers(1 << 31))
        created = self.client.create_match(scenario)
        self.match_id = created.id
        self._run(self._seat(created.bot_tokens))
        self.agents = list(self.possible_agents)
        self.steps = 0
        observations = {a: self._observe(a) for a in self.agents}
        infos = {a: {"tick": self._perceptions[a]["tick"]} for a in self.agents}
        return observations, infos

    def step(self, actions: dict):
        if not self.agents:
            raise RuntimeError("step() after the episode ended: call reset()")
        ended, rewards, rejected = self._run(self._play(actions))
        self.steps += 1
        truncated = not ended and self.max_steps is not None and self.steps >= self.max_steps
        agents = self.agents
        observations = {a: self._observe(a) for a in agents}
        terminations = {a: ended for a in agents}
        truncations = {a: truncated for a in agents}
        infos = {a: {"tick": self._perceptions[a]["tick"], "rejected": rejected[a]} for a in agents}
        if ended or truncated:
            self.agents = []
        return observations, {a: rewards[a] for a in agents}, terminations, truncations, infos

    def close(self) -> None:
        self._end_match()
        if not self._loop.is_closed():
            self._loop.close()

    # --- the match's sockets ---------------------------------------------------------

    def _run(self, coroutine):
        return self._loop.run_until_complete(coroutine)

    async def _seat(self, tokens: dict[str, str]) -> None:
        """Opens the spectator and the bots, then brings every bot to the same tick: the
        first bot's first perception T is answered by every bot (a command for T is in
        the window for a bot seated later, and answers for it: PROTOCOL.md, "Tick
        checks"), so the next tick perceives them all together."""
        if not self.fly:
            self._spectator = await Socket.open(self.client.spectate_url(self.match_id))
        url = self.client.play_url(self.match_id)
        for agent in self.possible_agents:
            self._bots[agent] = await Socket.open(url, tokens[agent])
        match = self._bots[self.possible_agents[0]].hello["match"]
        self._players = [a["id"] for a in match["agents"]]
        self._offense = {a["id"] for a in match["agents"] if a.get("team") == "offense"}
        self._points = 0
        first = await self._perceive(self.possible_agents[0])
        if first is None:
            raise FieldhouseError("the match ended before its first perception", code="ended")
        tick = first["tick"]
        for socket in self._bots.values():
            await socket.send({"type": "command", "tick": tick, "action": {"kind": "stand"}})
        for agent in self.possible_agents:
            perception = await self._perceive(agent, after=tick)
            if perception is None:
                raise FieldhouseError("the match ended while the bots were seated", code="ended")
        ticks = {p["tick"] for p in self._perceptions.values()}
        if len(ticks) != 1:
            raise FieldhouseError(
                f"the bots were seated at different ticks: {sorted(ticks)}", code="seat"
            )
        if not self.fly:
            # The frames before the episode: their points are not its.
            await self._read_frames(ticks.pop())

    async def _perceive(
        self, agent: str, after: int = -1, rejected: list | None = None
    ) -> dict | None:
        """The agent's next perception after tick ``after`` (None at the match's end);
        refusals of its commands go to ``rejected``."""
        socket = self._bots[agent]
        while True:
            try:
                message = await socket.recv()
            except ConnectionClosed:
                return None  # closed after the `end` (which a reset may have swallowed)
            kind = message.get("type")
            if kind == "perception" and message["tick"] > after:
                self._perceptions[agent] = message
                return message
            if kind == "end":
                return None
            if kind == "error" and rejected is not None:
                rejected.append(f"{message['code']}: {message['message']}")

    async def _play(self, actions: dict):
        """One step: a command per agent, then the next perceptions and the frames up to
        their tick. Returns whether the match ended, the rewards and the refusals."""
        for agent in self.agents:
            if agent not in actions:
                raise KeyError(f"no action for agent {agent!r}")
            tick = self._perceptions[agent]["tick"]
            text = '{"type":"command","tick":%d,"action":%s}' % (
                tick,
                self._action(agent, actions[agent]),
            )
            try:
                await self._bots[agent].send_text(text)
            except ConnectionClosed:
                pass  # the match ended on the tick perceived: its `end` is read below
        rejected: dict[str, list] = {a: [] for a in self.agents}
        ended = False
        caught = {a: self._caught(a) for a in self.agents}
        for agent in self.agents:
            before = self._perceptions[agent]["tick"]
            if await self._perceive(agent, before, rejected[agent]) is None:
                ended = True
        if self.fly:
            # The tick of a catch is perceived (the server perceives before it ends).
            return ended, {a: float(self._caught(a) - caught[a]) for a in self.agents}, rejected
        tick = max(p["tick"] for p in self._perceptions.values())
        points = await self._read_frames(None if ended else tick)
        return ended, self._points_rewards(points), rejected

    async def _read_frames(self, tick: int | None) -> int:
        """The points scored in the frames up to ``tick`` (to the match's end if None)."""
        before = self._points
        while True:
            try:
                message = await self._spectator.recv()
            except FieldhouseError:
                break  # the spectator socket closed after the end
            kind = message.get("type")
            if kind == "frame":
                self._points = message["score"].get("points", 0)
                if tick is not None and message["tick"] >= tick:
                    break
            elif kind == "end":
                break
        return self._points - before

    async def _close_sockets(self) -> None:
        for socket in [*self._bots.values(), self._spectator]:
            if socket is not None:
                await socket.close()
        self._bots.clear()
        self._spectator = None

    def _end_match(self) -> None:
        if self._loop.is_closed():
            return
        self._run(self._close_sockets())
        if self.match_id is not None:
            try:
                self.client.delete_match(self.match_id)
            except NotFound:
                pass  # already gone (an ended match expires)
            self.match_id = None
        self.agents = []

    # --- observations, actions, rewards ----------------------------------------------

    def _observe(self, agent: str) -> np.ndarray:
        p = self._perceptions[agent]["perception"]
        if self.fly:
            return fielder_observation(p)
        return self._court_observation(agent, p)

    def _court_observation(self, agent: str, p: dict) -> np.ndarray:
        ball = p["ball"]
        holder = ball.get("holder")
        out = [
            p["shot_clock_s"],
            *ball["position"],
            *(float(ball["state"] == s) for s in BALL_STATES),
        ]
        seen = {a["id"]: a for a in p["agents"]}
        for player in self._players:
            a = seen.get(player)
            if a is None:
                out.extend([0.0] * len(PLAYER_OBSERVATION))
                continue
            h = a["heading"]
            out.extend(
                (
                    *a["position"],
                    math.cos(h),
                    math.sin(h),
                    float(holder == player),
                    float(player == agent),
                    float(a["team"] == "offense"),
                )
            )
        return np.asarray(out, np.float32)

    def _action(self, agent: str, action: Any) -> str:
        """The action's JSON for the command (built by hand: one step sends many)."""
        if self.fly:
            # Plain floats: numpy's clip costs more than the rest of this on two numbers.
            ax, az = (min(max(float(v), -1.0), 1.0) for v in action)
            limit = self._perceptions[agent]["perception"]["limits"]["max_accel_m_s2"]
            return '{"kind":"accelerate","accel":[%r,%r]}' % (ax * limit, az * limit)
        a = int(action)
        if a == 0:
            return '{"kind":"stand"}'
        if a == 1:
            return '{"kind":"shoot"}'
        if 2 <= a < 10:
            p = self._perceptions[agent]["perception"]
            me = next(s for s in p["agents"] if s["id"] == agent)
            bearing = (a - 2) * math.pi / 4
            x = min(max(me["position"][0] + MOVE_M * math.cos(bearing), 0.0), COURT["length_m"])
            half = COURT["width_m"] / 2
            z = min(max(me["position"][1] + MOVE_M * math.sin(bearing), -half), half)
            return '{"kind":"move_to","target":[%r,%r]}' % (x, z)
        return '{"kind":"pass","to":"%s"}' % self._players[a - 10]

    def _caught(self, agent: str) -> int:
        """The balls the fielder has caught so far, as its latest perception says."""
        return self._perceptions[agent]["perception"].get("caught", 0)

    def _points_rewards(self, points: int) -> dict[str, float]:
        return {a: float(points if a in self._offense else -points) for a in self.agents}


def fielder_observation(p: dict) -> np.ndarray:
    """A fielder's perception (the ``perception`` object) as :data:`FIELDER_OBSERVATION`."""
    body = p["self"]
    optics = p.get("optics")
    if optics is None:
        seen = [0.0] * 7
    else:
        rates = optics.get("rates") or {"d_tan_psi_dt": 0.0, "d_alpha_dt": 0.0}
        seen = [
            1.0,
            optics["tan_psi"],
            rates["d_tan_psi_dt"],
            optics["alpha"],
            rates["d_alpha_dt"],
            optics["distance_m"],
            optics["t"],
        ]
    return np.asarray([*seen, *body["position"], *body["velocity"], *body["home"]], np.float32)


class FieldhouseGymEnv(gymnasium.Env):
    """A Gymnasium environment over a scenario with exactly one bot agent: the parallel
    environment's spaces, observations and rewards for that agent."""

    metadata = {"render_modes": []}

    def __init__(self, url: str, scenario: dict, **kwargs: Any):
        self.parallel = FieldhouseParallelEnv(url, scenario, **kwargs)
        if len(self.parallel.possible_agents) != 1:
            raise ValueError(
                f"a Gymnasium environment plays one agent; the scenario has bots "
                f"{self.parallel.possible_agents} (use FieldhouseParallelEnv)"
            )
        self.agent = self.parallel.possible_agents[0]
        self.observation_space = self.parallel.observation_space(self.agent)
        self.action_space = self.parallel.action_space(self.agent)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        observations, infos = self.parallel.reset(seed=seed, options=options)
        return observations[self.agent], infos[self.agent]

    def step(self, action):
        obs, rewards, terms, truncs, infos = self.parallel.step({self.agent: action})
        a = self.agent
        return obs[a], rewards[a], terms[a], truncs[a], infos[a]

    def close(self) -> None:
        self.parallel.close()
