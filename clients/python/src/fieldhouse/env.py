"""A PettingZoo ``ParallelEnv`` over a lock-step match, and a single-agent Gymnasium
wrapper (needs the ``env`` extra: ``pip install './clients/python[env]'``).

**Registered environments.** Importing this module registers two Gymnasium ids (or name
the module in the id: ``gymnasium.make("fieldhouse.env:fieldhouse/FlyBall-v0")``):

* ``fieldhouse/FlyBall-v0``: one fielder (``f0``) and :func:`fly_ball_scenario`'s fly to
  centre field; ``max_episode_steps`` 1250 (the longest flight the server simulates is
  20 s, 1200 ticks). Keywords: ``launches``, ``sport``, and the environment's own.
* ``fieldhouse/Basketball-v0``: one bot player (``agent="o1"``, or ``"o2"``, ``"d1"``) in
  :func:`basketball_scenario`'s 2-v-1, the others on their built-in brains, for
  ``possessions=2``; ``max_episode_steps`` 200 (a possession lasts at most its 24 s
  shot clock, 96 steps). Registered ``nondeterministic``: an episode may start a few
  ticks into its first possession (see below).

Every environment finds its server at ``url=``, else ``$FIELDHOUSE_URL``, else
``http://127.0.0.1:7878``, and creates and deletes its matches with ``admin_token=``,
else ``$FIELDHOUSE_ADMIN_TOKEN``. A server that does not answer is a
:class:`~fieldhouse.errors.FieldhouseError` (``unreachable``) that says how to start one.

**Episodes.** :meth:`FieldhouseParallelEnv.reset` creates a ``lockstep`` match on the
server from the scenario (sport, line-up: the agents with ``"bot": true`` are the
environment's agents; the others play their built-in strategies) with the match seed
``seed`` (else the next of a sequence the last seed given started), seats a bot on each
agent, and returns their first perceptions. :meth:`~FieldhouseParallelEnv.step` sends one
command per agent for the tick it perceived; the server plays on once every bot has
answered (PROTOCOL.md, "Modes") and the next perceptions are the observations. The match's
``end`` (the last scripted ball dead, ``options.possessions`` played, ``duration_s``) ends
the episode for every agent (*termination*); ``max_steps`` cuts it short (*truncation*).
``reset(options={"scenario_options": {...}})`` gives one episode other scenario options,
merged over the scenario's: ``{"launches": [...]}`` new balls, ``{"possessions": 10}`` a
longer game (a learner draws its balls this way; one the server refuses is
``BadScenario``). Other keys of ``options`` are not used (a warning names them).
:meth:`~FieldhouseParallelEnv.close` (and the next ``reset``) deletes the match, and so
does a ``reset`` that fails once the match is created: an episode leaves nothing behind.
Its matches are not recorded unless ``record=True`` (then the replay is named ``name``,
default ``"fieldhouse env"``, which the lobby also shows for the live match).

Until the bots are seated the match ticks in real time, its agents on their built-in
brains: :func:`fly_ball_scenario` therefore hits its first ball half a second in, and a
basketball episode may start a few ticks into its first possession.

**Rendering.** The environments draw nothing themselves (``render_modes`` is empty):
a match is watched live on the server's spectator page, at :attr:`spectator_url`
(``{url}/#/matches/{match_id}``). ``render()`` returns None and warns with that
address, as Gymnasium asks of an environment without a render mode; a ``render_mode``
is refused with it.

**Fielders** (baseball, cricket) perceive every tick, so a step is one tick (1/60 s).

* Observation: ``Box(13,)`` float32, :data:`FIELDER_OBSERVATION` in order:
  ``ball_in_play`` (0 or 1), then the optical variables ``tan_psi``, ``d_tan_psi_dt``,
  ``alpha``, ``d_alpha_dt``, ``distance_m``, ``t`` (0 between balls; rates 0 on a ball's
  first tick), then the fielder's own ``x``, ``z``, ``vx``, ``vz``, ``home_x``, ``home_z``
  (m, m/s). These are exactly the perception's fields (PROTOCOL.md, "`perception`").
  Their bounds are what the server lets a match do (:func:`fielder_observation_space`):
  ``alpha`` within ±π, ``d_alpha_dt`` within ±π·``tick_hz`` (a bearing changes by at
  most half a turn between ticks), ``t`` at most 20 s (the longest flight), the speeds
  within the body's ``max_speed_m_s``, the homes within 250 m of the batter (or the
  scenario's farthest), the position within the home's distance plus what the top
  speed covers between two launches (which put the fielder back home), ``distance_m``
  that plus the farthest a 70 m/s ball (the fastest launch) goes in 20 s. ``tan_psi``
  and ``d_tan_psi_dt`` are unbounded: a ball passing over the eye makes them as large
  as it likes.
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
  ``is_self``, ``offense``. Bounds (:func:`court_observation_space`): the shot clock
  from 0 to ``options.shot_clock_s`` (24), positions on the half court (x 0 to 14 m,
  z ±7.5 m) and the 1 m beyond its lines a run may use, the ball's height 0 to 5 m (a
  shot's arc peaks near 4.1 m), the rest 0 to 1 or ±1.
* Action: ``Discrete(10 + P)``: 0 ``stand``, 1 ``shoot``, 2 to 9 ``move_to`` a point 2 m
  away at bearing ``k·45°`` (k = action − 2, clamped to the court), 10 + i ``pass`` to
  player i. An action the player cannot take (a shot without the ball, a pass to a
  defender) is refused by the server and ignored; its message is in the info's
  ``rejected``.
* Reward: the offense's points scored during the step, for each offensive player; their
  negative for each defender.

An observation outside its space would mean the server did something these bounds say
it cannot: it is clipped into the space, with a ``RuntimeWarning`` naming the fields. An
action outside its space (a wrong shape or type, out of range, NaN) is a ``ValueError``
naming the agent, the action and the space, raised before any command is sent.

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
import reprlib
import warnings
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

#: The scenario's ``name`` for an environment's matches, unless given another.
DEFAULT_NAME = "fieldhouse env"

# What the server allows a fly-ball match (crates/core/src/sim/fly), which bounds what a
# fielder can perceive.
MAX_FLIGHT_S = 20.0  # a ball is simulated for at most 20 s
FARTHEST_HOME_M = 250.0  # a fielder's home is at most 250 m from the batter
HUMAN_MAX_SPEED_M_S = 8.5  # a body without scenario limits
DEFAULT_PAUSE_S = 2.0  # between one ball's end and the next launch
# The ball leaves the bat at most 70 m/s, 1 m up; drag only takes energy away, spin
# (a force across the motion) none, and falling 1 m adds less than 0.2 m/s: its ground
# point stays within 70.2 m/s x 21 s (20 s and a tick of at least 1/1 Hz) < 1500 m of
# the batter.
BALL_RANGE_M = 1500.0

# What the server allows a basketball match (crates/core/src/basketball).
SHOT_CLOCK_S = 24.0  # options.shot_clock_s by default
RUN_OFF_M = 1.0  # a move may carry a player this far beyond the lines, never farther
BALL_TOP_M = 5.0  # the highest the ball goes is a shot's arc, about 4.1 m

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


def fielder_observation_space(scenario: dict) -> spaces.Box:
    """The observation space of the scenario's bot fielders (one for all of them, so that
    a policy can be shared): each of :data:`FIELDER_OBSERVATION` within what the server
    lets this scenario's match do (the module's doc says how)."""
    tick_s = 1.0 / (scenario.get("tick_hz") or 60.0)
    bots = [a for a in scenario.get("agents") or [] if a.get("bot")]
    # A home the scenario leaves out is the default line-up's: within the farthest allowed.
    homes = [math.hypot(*a["position"]) if a.get("position") else FARTHEST_HOME_M for a in bots]
    home = max(homes, default=FARTHEST_HOME_M)
    speed = max(
        ((a.get("limits") or {}).get("max_speed_m_s", HUMAN_MAX_SPEED_M_S) for a in bots),
        default=HUMAN_MAX_SPEED_M_S,
    )
    # Each launch puts the fielder back home at rest; until the next, it runs at most
    # `speed` for a flight and the dead time after it, the pause or until a scripted time
    # (a bot's fielder follows its orders between balls too). Two ticks cover rounding.
    options = scenario.get("options") or {}
    pause_s = options.get("pause_s")
    pause_s = DEFAULT_PAUSE_S if pause_s is None else pause_s
    launch_times = [launch.get("time_s", 0.0) for launch in options.get("launches") or []]
    away_s = MAX_FLIGHT_S + max([pause_s, *launch_times]) + 2 * tick_s
    reach = home + speed * away_s
    bounds = {
        "ball_in_play": (0.0, 1.0),
        # (ball height - eye) / distance: a ball passing over the eye (distance near 0)
        # makes tan psi, and its rate, as large as it likes.
        "tan_psi": (-np.inf, np.inf),
        "d_tan_psi_dt": (-np.inf, np.inf),
        "alpha": (-math.pi, math.pi),
        # The server wraps the bearing's change to half a turn, over at least a tick.
        "d_alpha_dt": (-math.pi / tick_s, math.pi / tick_s),
        "distance_m": (0.0, reach + BALL_RANGE_M),
        "t": (0.0, MAX_FLIGHT_S + tick_s),
        "x": (-reach, reach),
        "z": (-reach, reach),
        "vx": (-speed, speed),
        "vz": (-speed, speed),
        "home_x": (-home, home),
        "home_z": (-home, home),
    }
    low, high = zip(*(bounds[name] for name in FIELDER_OBSERVATION), strict=True)
    return spaces.Box(np.array(low, np.float32), np.array(high, np.float32), dtype=np.float32)


def court_observation_space(scenario: dict) -> spaces.Box:
    """The observation space of the scenario's bot basketball players: the
    :data:`COURT_OBSERVATION`, then :data:`PLAYER_OBSERVATION` for each player, each
    within what the server lets the match do (the module's doc says how)."""
    options = scenario.get("options") or {}
    shot_clock_s = options.get("shot_clock_s") or SHOT_CLOCK_S
    x = (-RUN_OFF_M, COURT["length_m"] + RUN_OFF_M)
    z = (-COURT["width_m"] / 2 - RUN_OFF_M, COURT["width_m"] / 2 + RUN_OFF_M)
    flag = (0.0, 1.0)
    # The ball is held by a player, passed between two, or shot from one to the basket:
    # on the ground it is where the players are.
    court = [(0.0, shot_clock_s), x, (0.0, BALL_TOP_M), z, flag, flag, flag]
    player = [x, z, (-1.0, 1.0), (-1.0, 1.0), flag, flag, flag]
    low, high = zip(*court, *player * len(scenario["agents"]), strict=True)
    return spaces.Box(np.array(low, np.float32), np.array(high, np.float32), dtype=np.float32)


class FieldhouseParallelEnv(ParallelEnv):
    """The bot agents of ``scenario`` on the server at ``url`` (see the module's doc).

    ``url`` defaults to ``$FIELDHOUSE_URL``, else ``http://127.0.0.1:7878``;
    ``admin_token`` (default ``FIELDHOUSE_ADMIN_TOKEN``) creates and deletes the matches.
    ``max_steps`` truncates an episode; ``deadline_ms`` is how long the server waits for
    a command before playing a tick without it. ``record=True`` keeps a replay of each
    episode's match (on a server started with ``--replay-dir``), named ``name``.
    ``loop``: an event loop to share with other environments stepped together
    (:class:`fieldhouse.vector.FieldhouseVectorEnv`), which its owner closes; by default
    the environment has its own.
    """

    metadata = {"name": "fieldhouse_v0", "render_modes": []}

    def __init__(
        self,
        url: str | None = None,
        scenario: dict | None = None,
        *,
        admin_token: str | None = None,
        max_steps: int | None = None,
        deadline_ms: int = 5000,
        record: bool = False,
        name: str | None = None,
        render_mode: str | None = None,
        loop: asyncio.AbstractEventLoop | None = None,
    ):
        if scenario is None:
            raise TypeError("a scenario is needed: fly_ball_scenario(), basketball_scenario()")
        agents = scenario.get("agents")
        if not agents or not any(a.get("bot") for a in agents):
            raise ValueError('the scenario needs agents, at least one with "bot": true')
        self.client = Client(url, admin_token)
        if render_mode is not None:
            raise ValueError(
                f"render_mode {render_mode!r}: fieldhouse environments draw nothing "
                f"themselves; watch a match live on the server's spectator page, "
                f"{self.client.url}/#/matches/<match id> (the environment's spectator_url "
                "once reset)"
            )
        self.render_mode = None
        self.scenario = copy.deepcopy(scenario)
        self.scenario.update(mode="lockstep", lockstep_deadline_ms=deadline_ms)
        self.scenario["frame_hz"] = self.scenario.get("tick_hz") or 60.0
        self.scenario["name"] = name or self.scenario.get("name") or DEFAULT_NAME
        self.record = record
        self.sport = self.scenario["sport"]
        self.fly = self.sport in FLY_SPORTS
        self.max_steps = max_steps
        self.possible_agents = [a["id"] for a in agents if a.get("bot")]
        self.agents: list[str] = []
        if self.fly:
            obs = fielder_observation_space(self.scenario)
            act: spaces.Space = spaces.Box(-1.0, 1.0, (2,), np.float32)
            self._observation_names = list(FIELDER_OBSERVATION)
        else:
            obs = court_observation_space(self.scenario)
            act = spaces.Discrete(10 + len(agents))
            self._observation_names = [
                *COURT_OBSERVATION,
                *(f"{field}[{i}]" for i in range(len(agents)) for field in PLAYER_OBSERVATION),
            ]
        self.observation_spaces = {a: obs for a in self.possible_agents}
        self.action_spaces = {a: act for a in self.possible_agents}
        self.match_id: str | None = None
        self.steps = 0
        self._seeds = np.random.default_rng()
        self._owns_loop = loop is None
        self._loop = loop or asyncio.new_event_loop()
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

    @property
    def spectator_url(self) -> str | None:
        """The spectator page's live view of the episode's match (None between episodes)."""
        return None if self.match_id is None else self.client.view_url(self.match_id)

    def render(self) -> None:
        """Draws nothing: a match is watched live on the server's spectator page. Returns
        None, as Gymnasium and PettingZoo ask of an environment without a render mode,
        and warns with the page's address."""
        where = self.spectator_url or self.client.view_url() + " (the lobby: no match yet)"
        gymnasium.logger.warn(
            f"fieldhouse environments draw nothing themselves: watch the match live on the "
            f"server's spectator page, {where}"
        )

    # --- episodes --------------------------------------------------------------------

    def reset(self, seed: int | None = None, options: dict | None = None):
        self._end_match()
        # The match's seed: ``seed``, or else the next draw of a generator that the last
        # seed given started, so that episodes differ and a seeded run repeats.
        if seed is not None:
            self._seeds = np.random.default_rng(seed)
        scenario = copy.deepcopy(self.scenario)
        options = dict(options or {})
        episode = options.pop("scenario_options", None) or {}
        if options:
            warnings.warn(
                f"reset options {sorted(options)} are not used: give scenario options as "
                '{"scenario_options": {...}}',
                stacklevel=2,
            )
        # This episode's scenario options over the environment's: new balls (``launches``),
        # more possessions, and so on. The server checks them.
        scenario["options"] = {**(scenario.get("options") or {}), **episode}
        scenario["seed"] = int(seed) if seed is not None else int(self._seeds.integers(1 << 31))
        created = self.client.create_match(scenario, record=self.record)
        self.match_id = created.id
        try:
            self._run(self._seat(created.bot_tokens))
        except BaseException:
            # A match whose bots could not be seated is no episode: delete it rather than
            # leave it to the server (and, recorded, to the lobby).
            self._end_match()
            raise
        self.agents = list(self.possible_agents)
        self.steps = 0
        observations = {a: self._observe(a) for a in self.agents}
        infos = {a: {"tick": self._perceptions[a]["tick"]} for a in self.agents}
        return observations, infos

    def step(self, actions: dict):
        return self._finish(*self._run(self._play(self._commands(actions))))

    def _commands(self, actions: dict) -> dict[str, str]:
        """Each agent's action as its command's text. Every action is checked before any
        is sent: a refused step changes nothing."""
        if not self.agents:
            raise RuntimeError("step() after the episode ended: call reset()")
        commands = {}
        for agent in self.agents:
            if agent not in actions:
                raise KeyError(f"no action for agent {agent!r}")
            commands[agent] = self._command(agent, actions[agent])
        return commands

    def _finish(self, ended: bool, rewards: dict, rejected: dict):
        """A step's five results, from what :meth:`_play` brought back."""
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
        try:
            self._end_match()
        finally:
            if self._owns_loop and not self._loop.is_closed():
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

    async def _play(self, commands: dict[str, str]):
        """One step: a command per agent, then the next perceptions and the frames up to
        their tick. Returns whether the match ended, the rewards and the refusals."""
        for agent, text in commands.items():
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
        obs = fielder_observation(p) if self.fly else self._court_observation(agent, p)
        space = self.observation_spaces[agent]
        outside = (obs < space.low) | (obs > space.high)
        if outside.any():
            # The bounds are what the server allows; past them it changed, or they were
            # wrong. Keep the promise the space makes, and say so.
            names = [n for n, out in zip(self._observation_names, outside, strict=True) if out]
            warnings.warn(
                f"agent {agent!r}'s observation is outside its space at {', '.join(names)}: "
                f"clipped into it",
                RuntimeWarning,
                stacklevel=3,
            )
            np.clip(obs, space.low, space.high, out=obs)
        return obs

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

    def _command(self, agent: str, action: Any) -> str:
        """The command's JSON for the agent's action on its perceived tick (built by
        hand: one step sends many)."""
        tick = self._perceptions[agent]["tick"]
        return '{"type":"command","tick":%d,"action":%s}' % (tick, self._action(agent, action))

    def _action(self, agent: str, action: Any) -> str:
        """The action's JSON, or a ValueError if it is not in the agent's action space."""
        if self.fly:
            ax, az = self._acceleration(agent, action)
            limit = self._perceptions[agent]["perception"]["limits"]["max_accel_m_s2"]
            return '{"kind":"accelerate","accel":[%r,%r]}' % (ax * limit, az * limit)
        if not self.action_spaces[agent].contains(action):
            n = self.action_spaces[agent].n
            raise self._bad_action(agent, action, f"an integer from 0 to {n - 1}")
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

    def _acceleration(self, agent: str, action: Any) -> tuple[float, float]:
        """A fielder's action as two floats in [-1, 1]. Checked by hand rather than by
        ``Box.contains``, which costs more than the rest of a step's client work and
        refuses a float64 array (what numpy gives by default) for a float32 space."""
        try:
            a = action if isinstance(action, np.ndarray) else np.asarray(action)
        except ValueError:  # a ragged list
            raise self._bad_action(agent, action, "an array") from None
        if a.shape != (2,) or a.dtype.kind not in "fiu":
            raise self._bad_action(agent, action, "an array of two numbers")
        ax, az = a.tolist()
        # NaN fails both comparisons.
        if not (-1.0 <= ax <= 1.0 and -1.0 <= az <= 1.0):
            raise self._bad_action(agent, action, "each from -1 to 1 (clip a policy's output)")
        return ax, az

    def _bad_action(self, agent: str, action: Any, expected: str) -> ValueError:
        space = self.action_spaces[agent]
        if isinstance(action, np.ndarray):  # on one line, with what a list would not show
            given = f"{reprlib.repr(action.tolist())} (shape {action.shape}, {action.dtype})"
        else:
            given = reprlib.repr(action)
        meaning = (
            "an acceleration [ax, az] in units of the body's maximum"
            if self.fly
            else "0 stand, 1 shoot, 2 to 9 move 2 m at (a-2)*45 degrees, 10+i pass to player i"
        )
        return ValueError(
            f"the action for agent {agent!r}, {given}, is not in its action space {space}: "
            f"expected {expected} ({meaning})"
        )

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
    environment's spaces, observations and rewards for that agent. The keywords are
    :class:`FieldhouseParallelEnv`'s (``admin_token``, ``max_steps``, ``deadline_ms``,
    ``record``, ``name``)."""

    metadata = {"render_modes": []}

    def __init__(self, url: str | None = None, scenario: dict | None = None, **kwargs: Any):
        self.parallel = FieldhouseParallelEnv(url, scenario, **kwargs)
        if len(self.parallel.possible_agents) != 1:
            raise ValueError(
                f"a Gymnasium environment plays one agent; the scenario has bots "
                f"{self.parallel.possible_agents} (use FieldhouseParallelEnv)"
            )
        self.agent = self.parallel.possible_agents[0]
        self.observation_space = self.parallel.observation_space(self.agent)
        self.action_space = self.parallel.action_space(self.agent)

    @property
    def spectator_url(self) -> str | None:
        """The spectator page's live view of the episode's match (None between episodes)."""
        return self.parallel.spectator_url

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        # Seeds self.np_random, as Gymnasium asks; the match's seed is ``seed`` itself.
        super().reset(seed=seed)
        observations, infos = self.parallel.reset(seed=seed, options=options)
        return observations[self.agent], infos[self.agent]

    def step(self, action):
        obs, rewards, terms, truncs, infos = self.parallel.step({self.agent: action})
        a = self.agent
        return obs[a], rewards[a], terms[a], truncs[a], infos[a]

    def render(self) -> None:
        """Draws nothing: see :meth:`FieldhouseParallelEnv.render`."""
        return self.parallel.render()

    def close(self) -> None:
        self.parallel.close()


def fly_ball_env(
    url: str | None = None,
    *,
    launches: list[dict] | None = None,
    sport: str = "baseball",
    **kwargs: Any,
) -> FieldhouseGymEnv:
    """``fieldhouse/FlyBall-v0``: one fielder, ``f0``, and :func:`fly_ball_scenario`'s
    ``launches``; ``kwargs`` go to :class:`FieldhouseGymEnv`."""
    return FieldhouseGymEnv(url, fly_ball_scenario(1, launches, sport), **kwargs)


def basketball_env(
    url: str | None = None, *, agent: str = "o1", possessions: int = 2, **kwargs: Any
) -> FieldhouseGymEnv:
    """``fieldhouse/Basketball-v0``: ``agent`` (``o1``, ``o2`` or ``d1``) played by the
    environment in :func:`basketball_scenario`'s 2-v-1, for ``possessions``; ``kwargs``
    go to :class:`FieldhouseGymEnv`."""
    return FieldhouseGymEnv(url, basketball_scenario((agent,), possessions), **kwargs)


def _register() -> None:
    """Registers the ids with Gymnasium. Gymnasium 1.x no longer loads third-party ids
    from package entry points, so importing this module (or naming it in the id,
    ``fieldhouse.env:fieldhouse/FlyBall-v0``) is what makes them known."""
    ids = {
        # The longest flight the server simulates is 20 s: 1200 ticks, and the 0.5 s
        # before the launch.
        "fieldhouse/FlyBall-v0": dict(entry_point=fly_ball_env, max_episode_steps=1250),
        # Two possessions of at most a 24 s shot clock, 96 steps each. The first may
        # have begun a few ticks before the bot was seated, so a seed alone does not
        # fix an episode.
        "fieldhouse/Basketball-v0": dict(
            entry_point=basketball_env, max_episode_steps=200, nondeterministic=True
        ),
    }
    for env_id, spec in ids.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(env_id, **spec)


_register()
