"""Bots: programs that play one agent of a match over its WebSocket (PROTOCOL.md,
"Message flow").

Two styles over the same connection:

* a callback, ``on_perception(perception) -> action``, run by :meth:`Bot.run`;
* an async iterator, ``async for perception in bot: await bot.act(action)``.

Either way the bot reconnects with the same token when the connection drops before the
match's ``end`` (the server hands the agent back to the bot: PROTOCOL.md, "Connecting,
disconnecting, reconnecting"), and never after ``replaced`` (someone else took the agent
over) or a refusal (a wrong token is not going to become right).

:class:`Socket` is the layer below, raw JSON objects in and out, which the environments
in :mod:`fieldhouse.env` drive directly.
"""

from __future__ import annotations

import asyncio
import inspect
import json
import logging
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import websockets
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed as WsClosed
from websockets.exceptions import InvalidStatus

from .errors import (
    ConnectionClosed,
    Ended,
    FieldhouseError,
    ProtocolMismatch,
    Replaced,
    error_for,
)
from .messages import (
    PROTOCOL,
    VERSION,
    Action,
    End,
    Hello,
    Perception,
    action_to_wire,
    decode,
)

log = logging.getLogger("fieldhouse.bot")


class Socket:
    """One open WebSocket to the server, its ``hello`` read: JSON objects in and out.

    :meth:`recv` returns each message as a dict and turns the ways a socket can end into
    exceptions of :mod:`fieldhouse.errors`: a refused upgrade into its error code's class,
    a close without ``end`` into :class:`ConnectionClosed` (or :class:`Replaced`).
    """

    def __init__(self, ws: ClientConnection, hello: dict):
        self.ws = ws
        self.hello = hello

    @classmethod
    async def open(
        cls,
        url: str,
        token: str | None = None,
        open_timeout_s: float = 10.0,
        max_queue: int | None = 16,
        max_message_bytes: int | None = 16 * 2**20,
    ) -> Socket:
        """Connects to ``url`` (the token, if any, as a bearer header) and reads ``hello``,
        which must come within ``open_timeout_s``. ``max_queue`` messages received but
        not yet read are buffered (None: without limit; past a limit the socket stops
        reading, and the server drops a spectator that does not take its frames). A
        message longer than ``max_message_bytes`` closes the socket (1009): the server's
        own are at most a few kilobytes live and a megabyte from a replay (PROTOCOL.md,
        "Limits"), so the default leaves room and stops a server that never ends one."""
        headers = {"Authorization": f"Bearer {token}"} if token else None
        try:
            ws = await connect(
                url,
                additional_headers=headers,
                max_size=max_message_bytes,
                compression=None,
                open_timeout=open_timeout_s,
                max_queue=max_queue,
            )
        except InvalidStatus as e:
            raise _refusal(e) from None
        socket = cls(ws, {})
        # The upgrade answered is not a server that speaks: hello must follow in time.
        try:
            hello = await asyncio.wait_for(socket.recv(), open_timeout_s)
        except asyncio.TimeoutError:
            await ws.close()
            raise FieldhouseError(
                f"no hello from {url} within {open_timeout_s} s of the upgrade", code="timeout"
            ) from None
        if hello.get("type") != "hello":
            await ws.close()
            raise ProtocolMismatch(f"the first message was {hello.get('type')!r}, not hello")
        if hello.get("protocol") != PROTOCOL or hello.get("version") != VERSION:
            await ws.close()
            raise ProtocolMismatch(
                f"the server speaks {hello.get('protocol')!r} version {hello.get('version')!r}; "
                f"this client speaks {PROTOCOL!r} version {VERSION}"
            )
        socket.hello = hello
        return socket

    async def recv(self) -> dict:
        """The next message, as a JSON object. A message that is not one breaks the
        protocol: the socket is closed (1002) and :class:`ConnectionClosed` raised, so a
        bot reconnects as after any drop."""
        try:
            text = await self.ws.recv()
        except WsClosed as e:
            raise _closed(e) from None
        try:
            message = json.loads(text)
        except (ValueError, RecursionError) as e:
            why = f"the server sent a message that is not JSON ({type(e).__name__})"
        else:
            if isinstance(message, dict):
                return message
            why = f"the server sent a JSON {type(message).__name__}, not an object"
        await self.ws.close(1002, "not a JSON object")
        raise ConnectionClosed(why, close_code=1002)

    async def send(self, obj: dict) -> None:
        """Sends one message."""
        await self.send_text(json.dumps(obj, separators=(",", ":")))

    async def send_text(self, text: str) -> None:
        """Sends one message already encoded."""
        try:
            await self.ws.send(text)
        except WsClosed as e:
            raise _closed(e) from None

    async def close(self) -> None:
        await self.ws.close()


def _refusal(e: InvalidStatus) -> FieldhouseError:
    """A refused upgrade (its JSON body names the code) as its exception."""
    status = e.response.status_code
    try:
        err = json.loads(e.response.body)["error"]
        return error_for(err["code"], err["message"], status)
    except (ValueError, KeyError, TypeError, RecursionError):
        return FieldhouseError(
            f"the upgrade was refused with HTTP {status}", code="http", status=status
        )


def _closed(e: WsClosed) -> FieldhouseError:
    rcvd = e.rcvd
    if rcvd is None and e.sent is not None:
        # This side closed it (1009: a message over max_message_bytes) and heard no answer.
        return ConnectionClosed(
            f"the client closed the socket: {e.sent.code} {e.sent.reason}",
            close_code=e.sent.code,
        )
    code = rcvd.code if rcvd else None
    reason = rcvd.reason if rcvd else "no close frame"
    if code == 1008 and "another connection" in reason:
        return Replaced(reason)
    return ConnectionClosed(f"the server closed the socket: {code} {reason}", close_code=code)


OnPerception = Callable[[Perception], "Action | Awaitable[Action] | None"]
OnError = Callable[[FieldhouseError], Any]


def _log_error(error: FieldhouseError) -> None:
    log.warning("%s", error)


class Bot:
    """Plays the agent whose token is ``token`` in the match at ``url``
    (``ws://HOST:PORT/ws/matches/ID/play``; :meth:`Client.play_url` gives it).

    ``on_error`` receives each ``error`` the server sends about a command (``Rejected``,
    ``StaleTick``, ...; the connection stays open and the bot plays on); by default they
    are logged. ``reconnects`` bounds the reconnections after an unexpected drop, with
    ``backoff_s`` doubling from its start up to 2 s between tries.
    """

    def __init__(
        self,
        url: str,
        token: str,
        *,
        on_perception: OnPerception | None = None,
        on_error: OnError = _log_error,
        reconnects: int = 5,
        backoff_s: float = 0.1,
    ):
        self.url = url
        self.token = token
        self.on_perception = on_perception
        self.on_error = on_error
        self.reconnects = reconnects
        self.backoff_s = backoff_s
        self.hello: Hello | None = None
        self.end: End | None = None
        self.perception: Perception | None = None
        self.reconnections = 0
        self._socket: Socket | None = None

    async def connect(self) -> Hello:
        """Opens the socket (done for you by :meth:`run` and iteration)."""
        self._socket = await Socket.open(self.url, self.token)
        self.hello = decode(Hello, self._socket.hello)
        return self.hello

    async def act(self, action: Action, tick: int | None = None) -> None:
        """Sends ``action`` as the command for ``tick`` (default: the latest perception's).
        A command that meets a closed socket is dropped (see the iteration)."""
        if tick is None:
            if self.perception is None:
                raise ValueError("no perception to answer yet: pass tick=")
            tick = self.perception.tick
        if self._socket is None:
            raise ConnectionClosed("the bot is not connected")
        try:
            await self._socket.send(
                {"type": "command", "tick": int(tick), "action": action_to_wire(action)}
            )
        except ConnectionClosed:
            # The socket closed under the command: after the match's last tick (its `end`
            # is still to be read) or a failure the iteration reconnects from. Either way
            # the next perception, or the end, is the iteration's to report.
            pass

    async def close(self) -> None:
        """Closes the socket: the agent goes back to its built-in brain."""
        if self._socket is not None:
            await self._socket.close()
            self._socket = None

    async def __aiter__(self) -> AsyncIterator[Perception]:
        """Each perception in turn, until the match's ``end`` (then :attr:`end` holds it)."""
        while True:
            message = await self._next()
            if message is None:
                return
            yield message

    async def run(self) -> End | None:
        """Plays until the match ends, answering each perception with ``on_perception``'s
        action (``None``: no command this tick). Returns the match's ``end``."""
        if self.on_perception is None:
            raise ValueError("Bot.run needs on_perception=; or iterate: async for p in bot")
        async for perception in self:
            action = self.on_perception(perception)
            if inspect.isawaitable(action):
                action = await action
            if action is not None:
                await self.act(action, perception.tick)
        return self.end

    async def _next(self) -> Perception | None:
        """The next perception, handling everything else the socket brings; None at the end."""
        attempts = 0
        while True:
            try:
                if self._socket is None:
                    await self.connect()
                    attempts = 0
                message = await self._socket.recv()
            except Ended:
                if attempts == 0:
                    raise
                return None  # the match ended while the bot was away: nothing left to play
            except (
                ConnectionClosed,
                OSError,
                asyncio.TimeoutError,
                websockets.InvalidHandshake,
            ) as e:
                if self.end is not None:
                    return None
                if attempts >= self.reconnects:
                    raise
                attempts += 1
                self.reconnections += 1
                self._socket = None
                delay = min(self.backoff_s * 2 ** (attempts - 1), 2.0)
                log.info("connection lost (%s); reconnecting in %.1f s", e, delay)
                await asyncio.sleep(delay)
                continue
            kind = message.get("type")
            if kind == "perception":
                self.perception = Perception.from_wire(message)
                return self.perception
            if kind == "end":
                self.end = decode(End, message)
                await self.close()
                return None
            if kind == "error":
                error = error_for(message["code"], message["message"])
                if isinstance(error, Replaced):
                    await self.close()
                    raise error
                self.on_error(error)
            # Anything else (a type a newer server sends) is skipped, as PROTOCOL.md asks.
