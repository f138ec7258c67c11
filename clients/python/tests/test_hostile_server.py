"""The client against servers that misbehave, each played by a few lines of Python on a
loopback port: the client must not trust its server with its token, its time or its
exceptions."""

from __future__ import annotations

import asyncio
import http.server
import json
import threading
import time
import urllib.parse

import pytest
from websockets.asyncio.server import serve

from fieldhouse import Client
from fieldhouse.bot import Socket
from fieldhouse.errors import ConnectionClosed, FieldhouseError
from fieldhouse.messages import PROTOCOL, VERSION


class _Http(http.server.ThreadingHTTPServer):
    """A loopback HTTP server answering every request with ``answer(handler)``."""

    def __init__(self, answer):
        seen = self.seen = []

        class Handler(http.server.BaseHTTPRequestHandler):
            def _any(self):
                seen.append((self.command, self.path, self.headers.get("Authorization")))
                answer(self)

            do_GET = do_POST = do_DELETE = _any

            def log_message(self, *args):
                pass

        super().__init__(("127.0.0.1", 0), Handler)
        threading.Thread(target=self.serve_forever, daemon=True).start()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server_address[1]}"


def test_a_redirect_is_refused_and_the_admin_token_goes_nowhere():
    def elsewhere(h):
        h.send_response(200)
        h.end_headers()

    target = _Http(elsewhere)

    def redirect(h):
        h.send_response(302)
        h.send_header("Location", target.url + "/api/matches")
        h.send_header("Content-Length", "0")
        h.end_headers()

    redirector = _Http(redirect)
    try:
        client = Client(redirector.url, admin_token="the-admin-token-0123456789")
        with pytest.raises(FieldhouseError) as e:
            client.create_match({"sport": "baseball"})
        assert e.value.code == "redirect" and e.value.status == 302
        assert target.seen == [], "the request followed the redirect"
    finally:
        target.shutdown()
        redirector.shutdown()


def test_an_answer_that_is_not_json_is_a_fieldhouse_error():
    def garbage(h):
        body = b"[" * 100_000
        h.send_response(200)
        h.send_header("Content-Length", str(len(body)))
        h.end_headers()
        h.wfile.write(body)

    server = _Http(garbage)
    try:
        with pytest.raises(FieldhouseError) as e:
            Client(server.url).list_matches()
        assert e.value.code == "bad_response"
    finally:
        server.shutdown()


def test_an_endless_answer_is_cut_at_its_limit_and_a_trickle_at_its_deadline():
    def endless(h):
        h.send_response(200)
        h.send_header("Content-Length", str(2**62))
        h.end_headers()
        try:
            while True:
                h.wfile.write(b" " * 65536)
        except OSError:
            pass

    def trickle(h):
        h.send_response(200)
        h.send_header("Content-Length", "1000")
        h.end_headers()
        try:
            for _ in range(1000):
                h.wfile.write(b" ")
                h.wfile.flush()
                time.sleep(0.1)
        except OSError:
            pass

    big, slow = _Http(endless), _Http(trickle)
    try:
        with pytest.raises(FieldhouseError) as e:
            Client(big.url, max_answer_bytes=2**20).list_matches()
        assert e.value.code == "too_large"
        with pytest.raises(FieldhouseError) as e:
            Client(big.url, max_download_bytes=2**20).download_replay("r")
        assert e.value.code == "too_large"
        started = time.monotonic()
        with pytest.raises(FieldhouseError) as e:
            Client(slow.url, timeout_s=1.0).list_matches()
        assert e.value.code == "timeout"
        assert time.monotonic() - started < 3
    finally:
        big.shutdown()
        slow.shutdown()


HELLO = {"type": "hello", "protocol": PROTOCOL, "version": VERSION}


def _against(server_plays, client_does):
    """Runs ``client_does(url)`` against a WebSocket server on a loopback port that plays
    ``server_plays`` on each connection."""

    async def main():
        server = await serve(server_plays, "127.0.0.1", 0)
        try:
            await client_does(f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}/ws")
        finally:
            server.close()

    asyncio.run(main())


def _hello_then(message: str):
    """A server that sends hello, then ``message``, then waits."""

    async def plays(ws):
        await ws.send(json.dumps(HELLO))
        await ws.send(message)
        await asyncio.sleep(5)

    return plays


def test_an_upgrade_with_no_hello_times_out():
    async def silent(ws):
        await asyncio.sleep(30)

    async def opens(url):
        started = time.monotonic()
        with pytest.raises(FieldhouseError) as e:
            await Socket.open(url, open_timeout_s=0.5)
        assert e.value.code == "timeout"
        assert time.monotonic() - started < 5

    _against(silent, opens)


def test_a_message_over_the_cap_closes_the_socket():
    async def reads(url):
        socket = await Socket.open(url, open_timeout_s=5, max_message_bytes=2**20)
        with pytest.raises(ConnectionClosed) as e:
            await socket.recv()
        assert e.value.close_code == 1009

    _against(_hello_then(" " * (2 * 2**20)), reads)


@pytest.mark.parametrize("message", ["{not json", "[" * 100_000, '"a string"'])
def test_a_message_that_is_not_a_json_object_closes_the_socket_with_a_fieldhouse_error(message):
    async def reads(url):
        socket = await Socket.open(url, open_timeout_s=5)
        with pytest.raises(ConnectionClosed) as e:
            await socket.recv()
        assert e.value.close_code == 1002

    _against(_hello_then(message), reads)


def _listing(replays, *, repeat_cursor=False):
    """A server listing ``replays`` a page at a time, as fieldhouse does: ``limit`` and
    ``after`` (here the index of the last entry sent); with ``repeat_cursor`` it hands
    back the first page's cursor for ever."""

    def answer(h):
        query = urllib.parse.parse_qs(urllib.parse.urlparse(h.path).query)
        limit = int(query["limit"][0])
        start = 0 if "after" not in query else int(query["after"][0]) + 1
        page = replays[start : start + limit]
        more = start + limit < len(replays)
        cursor = str(limit - 1 if repeat_cursor else start + limit - 1)
        body = json.dumps({"replays": page, "next": cursor if more else None}).encode()
        h.send_response(200)
        h.send_header("Content-Length", str(len(body)))
        h.end_headers()
        h.wfile.write(body)

    return _Http(answer)


def test_replays_are_listed_by_following_the_pages_and_a_cursor_loop_is_refused():
    replays = [{"id": f"r{k}"} for k in range(5)]
    server = _listing(replays)
    looping = _listing(replays, repeat_cursor=True)
    try:
        client = Client(server.url)
        assert client.list_replays(page_size=2) == replays
        assert [p for _, p, _ in server.seen] == [
            "/api/replays?limit=2",
            "/api/replays?limit=2&after=1",
            "/api/replays?limit=2&after=3",
        ]
        server.seen.clear()
        assert client.list_replays(limit=3, page_size=2) == replays[:3]
        assert len(server.seen) == 2, "no page asked for past the limit"
        server.seen.clear()
        assert client.list_replays(limit=1) == replays[:1]
        assert [p for _, p, _ in server.seen] == ["/api/replays?limit=1"]
        with pytest.raises(FieldhouseError) as e:
            Client(looping.url).list_replays(page_size=2)
        assert e.value.code == "bad_response"
    finally:
        server.shutdown()
        looping.shutdown()
