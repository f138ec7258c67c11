"""The REST API (PROTOCOL.md, "HTTP endpoints"): matches and replays.

Plain ``urllib``: a bot or a training script makes a handful of these calls per match,
so a connection pool would buy nothing and cost a dependency. Every error answer
(``{"error": {"code", "message"}}``) is raised as its class from :mod:`fieldhouse.errors`.
"""

from __future__ import annotations

import json
import os
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from .errors import FieldhouseError, error_for

#: Where ``fieldhouse serve`` listens unless told otherwise.
DEFAULT_URL = "http://127.0.0.1:7878"


def server_url(url: str | None = None) -> str:
    """The server to talk to: ``url`` if given, else ``$FIELDHOUSE_URL``, else
    :data:`DEFAULT_URL` (a training script run elsewhere is pointed at its server by the
    environment, without a change to its code)."""
    return url or os.environ.get("FIELDHOUSE_URL") or DEFAULT_URL


class _NoRedirects(urllib.request.HTTPRedirectHandler):
    """fieldhouse never answers with a redirect, and following one would send the request,
    its admin token with it, wherever the answer points: refuse it."""

    def redirect_request(self, req, fp, code, msg, headers, newurl):
        raise FieldhouseError(
            f"{req.get_method()} {req.full_url} was answered with a redirect (HTTP {code}) "
            f"to {newurl}: fieldhouse never redirects, so it was not followed",
            code="redirect",
            status=code,
        )


_OPENER = urllib.request.build_opener(_NoRedirects)


@dataclass
class CreatedMatch:
    """The answer to ``POST /api/matches``: the id, and a token per bot agent (shown once)."""

    id: str
    bot_tokens: dict[str, str]


class Client:
    """A fieldhouse server's REST API at ``url`` (default: ``$FIELDHOUSE_URL``, else
    ``http://127.0.0.1:7878``).

    ``admin_token`` (default: ``FIELDHOUSE_ADMIN_TOKEN``) is needed to create and delete
    matches; listing and replays need none. Every request is bounded: an answer takes at
    most ``timeout_s`` in all (``download_timeout_s`` for a replay) and holds at most
    ``max_answer_bytes`` (``max_download_bytes`` for a replay); past either the request
    raises ``FieldhouseError`` (``timeout``, ``too_large``). A server that cannot be
    reached (none listening, a wrong address) is ``FieldhouseError`` ``unreachable``,
    whose message says how to start one.
    """

    def __init__(
        self,
        url: str | None = None,
        admin_token: str | None = None,
        timeout_s: float = 10.0,
        *,
        max_answer_bytes: int = 64 * 2**20,
        download_timeout_s: float = 600.0,
        max_download_bytes: int = 4 * 2**30,
    ):
        self.url = server_url(url).rstrip("/")
        self.admin_token = admin_token or os.environ.get("FIELDHOUSE_ADMIN_TOKEN")
        self.timeout_s = timeout_s
        self.max_answer_bytes = max_answer_bytes
        self.download_timeout_s = download_timeout_s
        self.max_download_bytes = max_download_bytes

    # --- matches ---------------------------------------------------------------------

    def create_match(self, scenario: dict, *, record: bool = True) -> CreatedMatch:
        """Creates a match from a scenario (``proto/scenario.schema.json``). With
        ``record=False`` a server that records matches (``--replay-dir``) keeps no replay
        of this one (``POST /api/matches?record=false``): a learner's thousands of
        episodes would each leave one in the lobby."""
        path = "/api/matches" if record else "/api/matches?record=false"
        body = self._json("POST", path, scenario, admin=True)
        return CreatedMatch(id=body["id"], bot_tokens=body.get("bot_tokens", {}))

    def list_matches(self) -> list[dict]:
        """Every match the server holds: sport, mode, status, tick, score, agents."""
        return self._json("GET", "/api/matches")["matches"]

    def get_match(self, match_id: str) -> dict:
        """One match in full: the summary, ``match`` (as in hello) and ``scenario``."""
        return self._json("GET", f"/api/matches/{_segment(match_id)}")

    def delete_match(self, match_id: str) -> None:
        """Ends the match (its clients get ``end`` with reason ``deleted``) and removes it."""
        self._json("DELETE", f"/api/matches/{_segment(match_id)}", admin=True)

    # --- replays ---------------------------------------------------------------------

    def list_replays(self, limit: int | None = None, *, page_size: int = 100) -> list[dict]:
        """The server's replays, newest first (empty if it records none): every one, asked
        for ``page_size`` at a time (``GET /api/replays?limit=N&after=CURSOR``), or the
        newest ``limit``."""
        if limit is not None and limit < 1:
            raise ValueError(f"limit {limit} is not a positive count")
        replays: list[dict] = []
        for replay in self.iter_replays(
            page_size=page_size if limit is None else min(page_size, limit)
        ):
            replays.append(replay)
            if limit is not None and len(replays) >= limit:
                break
        return replays

    def iter_replays(self, *, page_size: int = 100) -> Iterator[dict]:
        """The server's replays, newest first, a page of ``page_size`` (1 to 1000) asked for
        at a time as the iteration reaches it, following each page's ``next`` cursor. A
        server that hands back a cursor it gave before is refused (``bad_response``)
        rather than followed round for ever."""
        if not 1 <= page_size <= 1000:
            raise ValueError(f"page_size {page_size} is not from 1 to 1000")
        after = None
        seen: set[str] = set()
        while True:
            query = {"limit": page_size} if after is None else {"limit": page_size, "after": after}
            page = self._json("GET", "/api/replays?" + urllib.parse.urlencode(query))
            yield from page["replays"]
            after = page.get("next")
            if not after:
                return
            if after in seen:
                raise FieldhouseError(
                    f"the replay listing gave the cursor {after!r} twice", code="bad_response"
                )
            seen.add(after)

    def download_replay(self, replay_id: str, path: str | os.PathLike | None = None) -> bytes | int:
        """The replay file as stored (format 2: zstd): its bytes, or, with ``path``, streamed
        into that file (never held whole) and its size in bytes returned."""
        route = f"/api/replays/{_segment(replay_id)}"
        bounds = {"limit": self.max_download_bytes, "within_s": self.download_timeout_s}
        if path is None:
            return self._request("GET", route, **bounds)
        with open(path, "wb") as out:
            return self._request("GET", route, into=out, **bounds)

    # --- WebSocket addresses ---------------------------------------------------------

    def ws_url(self, path: str) -> str:
        """The ``ws://`` (or ``wss://``) address of a socket route on this server."""
        scheme, rest = self.url.split("://", 1)
        return f"{'wss' if scheme == 'https' else 'ws'}://{rest}{path}"

    def play_url(self, match_id: str) -> str:
        """Where a bot of ``match_id`` connects (its token goes in a header)."""
        return self.ws_url(f"/ws/matches/{_segment(match_id)}/play")

    def spectate_url(self, match_id: str) -> str:
        """Where a spectator of ``match_id`` connects."""
        return self.ws_url(f"/ws/matches/{_segment(match_id)}")

    def view_url(self, match_id: str | None = None) -> str:
        """The spectator page, for a browser: the live view of ``match_id`` (the page's
        route ``#/matches/ID``), or the lobby of every match."""
        if match_id is None:
            return f"{self.url}/"
        return f"{self.url}/#/matches/{_segment(match_id)}"

    # --- plumbing --------------------------------------------------------------------

    def _json(self, method: str, path: str, body: Any = None, *, admin: bool = False) -> Any:
        raw = self._request(method, path, body, admin=admin)
        try:
            return json.loads(raw)
        except (ValueError, RecursionError) as e:
            raise FieldhouseError(
                f"the answer to {method} {path} is not JSON: {e}", code="bad_response"
            ) from None

    def _request(
        self,
        method: str,
        path: str,
        body: Any = None,
        *,
        admin: bool = False,
        limit: int | None = None,
        within_s: float | None = None,
        into: Any = None,
    ) -> Any:
        headers = {"Accept": "application/json"}
        data = None
        if body is not None:
            data = json.dumps(body).encode()
            headers["Content-Type"] = "application/json"
        if admin:
            if not self.admin_token:
                raise FieldhouseError(
                    f"{method} {path} needs the admin token: pass admin_token= "
                    "or set FIELDHOUSE_ADMIN_TOKEN",
                    code="unauthorized",
                )
            headers["Authorization"] = f"Bearer {self.admin_token}"
        request = urllib.request.Request(self.url + path, data, headers, method=method)
        deadline = time.monotonic() + (self.timeout_s if within_s is None else within_s)
        limit = self.max_answer_bytes if limit is None else limit
        try:
            with _OPENER.open(request, timeout=self.timeout_s) as answer:
                return _read(answer, f"{method} {path}", limit, deadline, into)
        except urllib.error.HTTPError as e:
            raise _http_error(e) from None
        except urllib.error.URLError as e:
            # No answer at all: most often no server was started. Say how to start one,
            # rather than leave a socket error that names neither fieldhouse nor the fix.
            raise FieldhouseError(
                f"{method} {path}: no fieldhouse server answers at {self.url} ({e.reason}). "
                "Start one with `fieldhouse serve` (or `cargo run --release -- serve` in a "
                "clone of the repository), or point url= or FIELDHOUSE_URL at a running one",
                code="unreachable",
            ) from None


def _read(answer: Any, what: str, limit: int, deadline: float, into: Any) -> Any:
    """The answer's body, read as it comes (``read1``: a server that trickles cannot hold
    one read for long), at most ``limit`` bytes by ``deadline``: its bytes, or with
    ``into`` written there and counted."""
    chunks = []
    total = 0
    while chunk := answer.read1(64 * 1024):
        total += len(chunk)
        if total > limit:
            raise FieldhouseError(
                f"the answer to {what} is longer than {limit} bytes", code="too_large"
            )
        if time.monotonic() > deadline:
            raise FieldhouseError(
                f"the answer to {what} is still coming at its deadline", code="timeout"
            )
        if into is None:
            chunks.append(chunk)
        else:
            into.write(chunk)
    return total if into is not None else b"".join(chunks)


def _segment(s: str) -> str:
    return urllib.parse.quote(s, safe="")


def _http_error(e: urllib.error.HTTPError) -> FieldhouseError:
    # An error body is a line of JSON; a server that sends more is not read further.
    raw = e.read(64 * 1024)
    try:
        err = json.loads(raw)["error"]
        return error_for(err["code"], err["message"], e.code)
    except (ValueError, KeyError, TypeError, RecursionError):
        text = raw.decode(errors="replace").strip() or e.reason
        return FieldhouseError(str(text), code="http", status=e.code)
