"""The protocol's messages as dataclasses (PROTOCOL.md, "Messages").

Each class mirrors one object of a schema in ``proto/``: its fields are the schema's
properties (``tests/test_messages.py`` checks every class against the schema files, so a
change of the protocol that this module misses fails the tests). Field names are the
wire's, except where the wire's name is a Python keyword or ``self``: a fielder's own
body is ``body`` (wire ``self``), a player's own id is ``self_id``.

Decoding ignores keys it does not know, because the protocol adds fields within a version
(PROTOCOL.md, "Versioning"); encoding writes exactly the schema's fields, because the
server refuses unknown ones in commands.
"""

from __future__ import annotations

import json
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, ClassVar, Union

PROTOCOL = "fieldhouse"
VERSION = 3


def _wire(name: str, **kw: Any) -> Any:
    """A field whose wire name differs from its Python name."""
    metadata = dict(kw.pop("metadata", {}), wire=name)
    return field(metadata=metadata, **kw)


def _nested(cls: type, *, many: bool = False, **kw: Any) -> Any:
    """A field holding another message object (or a list of them)."""
    metadata = dict(kw.pop("metadata", {}), nested=cls, many=many)
    return field(metadata=metadata, **kw)


def decode(cls: type, obj: dict) -> Any:
    """``obj`` (a JSON object) as an instance of the dataclass ``cls``."""
    kwargs = {}
    for f in fields(cls):
        key = f.metadata.get("wire", f.name)
        if key not in obj:
            if f.default is MISSING and f.default_factory is MISSING:
                raise ValueError(f"{cls.__name__}: missing field {key!r}")
            continue
        value = obj[key]
        nested = f.metadata.get("nested")
        if nested is not None and value is not None:
            if f.metadata.get("many"):
                value = [decode(nested, v) for v in value]
            else:
                value = decode(nested, value)
        kwargs[f.name] = value
    return cls(**kwargs)


# --- hello -------------------------------------------------------------------------


@dataclass
class Limits:
    """``hello.limits``: the size limit and sustained rate in force."""

    max_message_bytes: int
    messages_per_second: float


@dataclass
class AgentInfo:
    """One agent of ``hello.match.agents``, in the order of the frames."""

    id: str
    team: str
    strategy: str
    home: list[float] | None = None


@dataclass
class MatchInfo:
    """``hello.match``: the match as the server describes it."""

    id: str
    sport: str
    mode: str
    seed: int
    tick_hz: float
    frame_hz: float
    perception_every_ticks: int
    field: dict
    agents: list[AgentInfo] = _nested(AgentInfo, many=True)
    motion_source: str = ""
    name: str | None = None


@dataclass
class Hello:
    """The first message on every socket."""

    protocol: str
    version: int
    role: str
    match: MatchInfo = _nested(MatchInfo)
    limits: Limits = _nested(Limits)
    agent: str | None = None
    replay: dict | None = None


# --- perception --------------------------------------------------------------------


@dataclass
class Rates:
    """How the optics changed since the previous tick."""

    d_tan_psi_dt: float
    d_alpha_dt: float


@dataclass
class Optics:
    """The ball as a fielder's eye sees it (PROTOCOL.md, "`perception`")."""

    tan_psi: float
    alpha: float
    distance_m: float
    t: float
    rates: Rates | None = _nested(Rates, default=None)


@dataclass
class SelfSensed:
    """A fielder's own body: ``[x, z]`` position and velocity, and its home."""

    position: list[float]
    velocity: list[float]
    home: list[float]


@dataclass
class BodyLimits:
    """A fielder's maximum speed and acceleration."""

    max_speed_m_s: float
    max_accel_m_s2: float


@dataclass
class FielderPerception:
    """What a fielder (baseball, cricket) perceives: its body and the ball's optics."""

    body: SelfSensed = _wire("self", metadata={"nested": SelfSensed, "many": False})
    ball_in_play: bool = False
    #: Balls this fielder has caught in the match so far.
    caught: int = 0
    limits: BodyLimits = _nested(BodyLimits, default=None)
    optics: Optics | None = _nested(Optics, default=None)


@dataclass
class SeenPlayer:
    """A basketball player as another player sees it."""

    id: str
    team: str
    position: list[float]
    heading: float
    action: str


@dataclass
class HoopsBall:
    """The basketball: ``held`` (with ``holder``), ``pass`` or ``shot``."""

    state: str
    position: list[float]
    holder: str | None = None


@dataclass
class PlayerPerception:
    """What a basketball player perceives: the whole court."""

    self_id: str = _wire("self")
    team: str = ""
    has_ball: bool = False
    agents: list[SeenPlayer] = _nested(SeenPlayer, many=True, default_factory=list)
    ball: HoopsBall = _nested(HoopsBall, default=None)
    shot_clock_s: float = 0.0
    basket: list[float] = field(default_factory=list)


Sensed = Union[FielderPerception, PlayerPerception]


@dataclass
class Perception:
    """What the bot's agent perceives at ``tick``; answer it with a command for ``tick``."""

    tick: int
    time_s: float
    agent: str
    perception: Sensed

    @classmethod
    def from_wire(cls, obj: dict) -> Perception:
        sensed = obj["perception"]
        kind = FielderPerception if "ball_in_play" in sensed else PlayerPerception
        return cls(obj["tick"], obj["time_s"], obj["agent"], decode(kind, sensed))


# --- end, error, frame -------------------------------------------------------------


@dataclass
class End:
    """The match is over: why, and the final score (the frames' ``score`` object)."""

    match: str
    tick: int
    reason: str
    result: dict | None = None


@dataclass
class ErrorMessage:
    """Something the client sent was refused; the connection stays open."""

    code: str
    message: str


@dataclass
class Frame:
    """The world at one tick, as spectators see it; sport-specific parts stay JSON."""

    match: str
    tick: int
    time_s: float
    ball: dict
    agents: list[dict]
    score: dict
    events: list[dict] = field(default_factory=list)


# --- commands ----------------------------------------------------------------------


@dataclass
class Accelerate:
    """Fielder: accelerate along ``[ax, az]`` m/s² (clipped to the body's limits)."""

    accel: tuple[float, float]
    kind: ClassVar[str] = "accelerate"


@dataclass
class RunTo:
    """Fielder: run to ``[x, z]`` and stop there (within 250 m of the batter)."""

    target: tuple[float, float]
    kind: ClassVar[str] = "run_to"


@dataclass
class MoveTo:
    """Basketball: move toward ``[x, z]`` on the court, dribbling with the ball."""

    target: tuple[float, float]
    kind: ClassVar[str] = "move_to"


@dataclass
class Pass:
    """Basketball: pass to the teammate ``to``."""

    to: str
    kind: ClassVar[str] = "pass"


@dataclass
class Shoot:
    """Basketball: shoot from here."""

    kind: ClassVar[str] = "shoot"


@dataclass
class Stand:
    """Stop: a fielder brakes to rest, a player stands."""

    kind: ClassVar[str] = "stand"


Action = Union[Accelerate, RunTo, MoveTo, Pass, Shoot, Stand]
ACTIONS: tuple[type, ...] = (Accelerate, RunTo, MoveTo, Pass, Shoot, Stand)


def action_to_wire(action: Action) -> dict:
    """The action as the command's ``action`` object: ``kind`` and exactly its fields,
    numbers as floats (the server wants arrays of exactly two numbers)."""
    out: dict[str, Any] = {"kind": action.kind}
    for f in fields(action):
        value = getattr(action, f.name)
        if f.name in ("accel", "target"):
            x, z = value
            value = [float(x), float(z)]
        out[f.name] = value
    return out


def encode_command(tick: int, action: Action) -> str:
    """The ``command`` message answering the perception of ``tick``, as JSON text."""
    return json.dumps(
        {"type": "command", "tick": int(tick), "action": action_to_wire(action)},
        separators=(",", ":"),
    )


# --- dispatch ----------------------------------------------------------------------

ServerMessage = Union[Hello, Perception, End, ErrorMessage, Frame, dict]


def parse(text: str | bytes) -> ServerMessage:
    """A server message as its dataclass; a type this release does not know stays a dict."""
    obj = json.loads(text)
    kind = obj.get("type")
    if kind == "perception":
        return Perception.from_wire(obj)
    if kind == "frame":
        return decode(Frame, obj)
    if kind == "hello":
        return decode(Hello, obj)
    if kind == "end":
        return decode(End, obj)
    if kind == "error":
        return decode(ErrorMessage, obj)
    return obj
