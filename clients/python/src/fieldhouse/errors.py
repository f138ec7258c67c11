"""One exception class per error code of the protocol (PROTOCOL.md, "Errors" and
"`error`"), so a program can catch exactly what it can handle: ``except Rejected`` for a
command the agent could not carry out, ``except BadScenario`` for a scenario the server
refused. Every class derives from :class:`FieldhouseError`, which keeps the wire's
``code``, its ``message`` and, for HTTP answers, the ``status``.

A code this release does not know (the protocol may add some) becomes a plain
:class:`FieldhouseError` with its code, as PROTOCOL.md asks clients to treat it.
"""

from __future__ import annotations


class FieldhouseError(Exception):
    """An error the server reported: ``code`` for programs, ``message`` for people."""

    code = "error"

    def __init__(self, message: str, *, code: str | None = None, status: int | None = None):
        super().__init__(message)
        self.message = message
        if code is not None:
            self.code = code
        self.status = status

    def __str__(self) -> str:
        where = f"HTTP {self.status} " if self.status is not None else ""
        return f"{where}{self.code}: {self.message}"


# --- REST answers and refused WebSocket upgrades (PROTOCOL.md, "Errors") -------------


class BadId(FieldhouseError):
    """400: a replay id with characters other than letters, digits, ``-`` and ``_``."""

    code = "bad_id"


class BadRequest(FieldhouseError):
    """400: a plain GET (no WebSocket upgrade) of a ``/ws/`` path."""

    code = "bad_request"


class BadQuery(FieldhouseError):
    """400: a replay listing's ``limit`` outside 1 to 1000, or an ``after`` that is no cursor."""

    code = "bad_query"


class Unauthorized(FieldhouseError):
    """401: no admin token (REST) or no bot token (``/play``)."""

    code = "unauthorized"


class Forbidden(FieldhouseError):
    """403: a wrong admin token, a bot token of no agent of this match, or a refused origin."""

    code = "forbidden"


class NotFound(FieldhouseError):
    """404: no such match (also once deleted), replay or route."""

    code = "not_found"


class NoReplays(FieldhouseError):
    """404: a replay asked of a server started without ``--replay-dir``."""

    code = "no_replays"


class NoCostmap(FieldhouseError):
    """404: a cost map of a sport or behaviour that has none."""

    code = "no_costmap"


class MethodNotAllowed(FieldhouseError):
    """405: a method the path does not take."""

    code = "method_not_allowed"


class RequestTimeout(FieldhouseError):
    """408: the request took longer than the server's ``request_timeout_ms``."""

    code = "timeout"


class Ended(FieldhouseError):
    """410: ``/play`` for a match that has ended."""

    code = "ended"


class TooLarge(FieldhouseError):
    """413: a request body over the server's ``max_body_bytes``."""

    code = "too_large"


class BadScenario(FieldhouseError):
    """422: the scenario is invalid; the message starts with the path of the field at fault."""

    code = "bad_scenario"


class BadReplay(FieldhouseError):
    """422: a replay file that is not readable."""

    code = "bad_replay"


class TooManyConnections(FieldhouseError):
    """429: this address already holds its maximum of open sockets."""

    code = "too_many_connections"


class TooManyMatches(FieldhouseError):
    """503: the server already runs its maximum of matches."""

    code = "too_many_matches"


class ServerBusy(FieldhouseError):
    """503: near the server's connection limit, a new spectator or replay viewer."""

    code = "server_busy"


class Overloaded(FieldhouseError):
    """503: too many REST requests in flight."""

    code = "overloaded"


class ReplaysUnavailable(FieldhouseError):
    """503: the replay directory cannot be read now (out of descriptors, say); try again."""

    code = "replays_unavailable"


# --- `error` messages on a WebSocket (PROTOCOL.md, "`error`") ---------------------------


class MalformedJson(FieldhouseError):
    """The text sent was not JSON."""

    code = "malformed_json"


class BadMessage(FieldhouseError):
    """JSON, but not a valid command (unknown or missing field, wrong type, a key twice)."""

    code = "bad_message"


class Binary(FieldhouseError):
    """A binary frame was sent; the protocol is JSON text."""

    code = "binary"


class RateLimited(FieldhouseError):
    """Messages are being dropped for exceeding the rate."""

    code = "rate_limited"


class Rejected(FieldhouseError):
    """A valid command the agent cannot carry out (wrong sport, no ball, out of range)."""

    code = "rejected"


class StaleTick(FieldhouseError):
    """The command's tick is more than four perception periods old."""

    code = "stale_tick"


class FutureTick(FieldhouseError):
    """The command's tick is more than one perception period ahead."""

    code = "future_tick"


class Replaced(FieldhouseError):
    """Another connection with this agent's token took it over; this one gets nothing more."""

    code = "replaced"


class BadControl(FieldhouseError):
    """Replay viewers: a ``control`` message was refused."""

    code = "bad_control"


# --- the connection itself --------------------------------------------------------------


class ConnectionClosed(FieldhouseError):
    """The server closed the socket without an ``end``: ``close_code`` says why (1008:
    flooding or taken over, 1009: a message over the size limit, 1001: shutdown, 1002:
    a frame that breaks the WebSocket protocol, 1007: text that is not UTF-8)."""

    code = "closed"

    def __init__(self, message: str, *, close_code: int | None = None):
        super().__init__(message)
        self.close_code = close_code


class ProtocolMismatch(FieldhouseError):
    """The server's ``hello`` names another protocol or version than this client speaks."""

    code = "protocol_mismatch"


ERRORS_BY_CODE: dict[str, type[FieldhouseError]] = {
    cls.code: cls
    for cls in (
        BadId,
        BadRequest,
        BadQuery,
        Unauthorized,
        Forbidden,
        NotFound,
        NoReplays,
        NoCostmap,
        MethodNotAllowed,
        RequestTimeout,
        Ended,
        TooLarge,
        BadScenario,
        BadReplay,
        TooManyConnections,
        TooManyMatches,
        ServerBusy,
        Overloaded,
        ReplaysUnavailable,
        MalformedJson,
        BadMessage,
        Binary,
        RateLimited,
        Rejected,
        StaleTick,
        FutureTick,
        Replaced,
        BadControl,
    )
}


def error_for(code: str, message: str, status: int | None = None) -> FieldhouseError:
    """The exception for a wire error: its own class, or a generic one for a new code."""
    cls = ERRORS_BY_CODE.get(code)
    if cls is None:
        return FieldhouseError(message, code=code, status=status)
    return cls(message, status=status)
