"""Bots against the real server: both styles, typed messages, every way a socket is
refused or taken away, and reconnection with the same token."""

from __future__ import annotations

import asyncio
import math
import time

import pytest

from fieldhouse import Bot, FielderPerception, MoveTo, PlayerPerception, RunTo, Stand
from fieldhouse.errors import (
    Ended,
    FieldhouseError,
    Forbidden,
    FutureTick,
    NotFound,
    Rejected,
    Replaced,
    StaleTick,
)

BALLS = [
    {"time_s": 0.5, "speed_m_s": 34.0, "elevation_deg": 45.0, "azimuth_deg": 45.0},
    {"time_s": 0.0, "speed_m_s": 30.0, "elevation_deg": 50.0, "azimuth_deg": 40.0},
]


def fielder_match(client, mode: str = "lockstep", launches=BALLS):
    created = client.create_match(
        {
            "sport": "baseball",
            "mode": mode,
            "agents": [{"id": "cf", "bot": True}],
            "options": {"pause_s": 0.2, "launches": launches},
        }
    )
    return client.play_url(created.id), created.bot_tokens["cf"], created.id


def under_the_ball(p):
    """bot.mjs's policy: run to the ball's ground point (home between balls)."""
    f = p.perception
    if f.optics is None:
        return RunTo(f.body.home)
    x, z = f.body.position
    return RunTo(
        (
            x + f.optics.distance_m * math.cos(f.optics.alpha),
            z + f.optics.distance_m * math.sin(f.optics.alpha),
        )
    )


def test_callback_style_plays_to_the_end(client):
    url, token, _ = fielder_match(client)
    seen = []

    def on_perception(p):
        seen.append(p)
        return under_the_ball(p)

    bot = Bot(url, token, on_perception=on_perception)
    end = asyncio.run(bot.run())
    assert (
        bot.hello.role == "bot" and bot.hello.agent == "cf" and bot.hello.match.sport == "baseball"
    )
    assert end.reason == "finished" and end.result["balls"] == 2
    assert all(isinstance(p.perception, FielderPerception) for p in seen)
    # Lock-step: every tick perceived, none skipped, from the first after joining.
    ticks = [p.tick for p in seen]
    assert ticks == list(range(ticks[0], ticks[0] + len(ticks)))
    assert any(
        p.perception.optics is not None and p.perception.optics.rates is not None for p in seen
    )


def test_iterator_style_and_async_callbacks(client):
    url, token, _ = fielder_match(client)

    async def play():
        bot = Bot(url, token)
        count = 0
        async for p in bot:
            count += 1
            await bot.act(under_the_ball(p))
        return bot, count

    bot, count = asyncio.run(play())
    assert bot.end is not None and bot.end.reason == "finished" and count > 300

    url, token, _ = fielder_match(client)

    async def slow_policy(p):
        await asyncio.sleep(0)
        return Stand()

    assert asyncio.run(Bot(url, token, on_perception=slow_policy).run()).result["balls"] == 2


def test_errors_about_commands_reach_on_error_and_play_goes_on(client):
    url, token, match_id = fielder_match(client)
    errors: list[FieldhouseError] = []

    async def play():
        bot = Bot(url, token, on_error=errors.append)
        async for p in bot:
            if p.tick % 3 == 0:
                await bot.act(MoveTo((1.0, 1.0)))  # a basketball action: rejected
            await bot.act(Stand(), tick=p.tick + 100)  # future_tick
            if p.tick > 10:
                await bot.act(Stand(), tick=0)  # stale_tick
            await bot.act(Stand())
            if len({type(e) for e in errors}) == 3:
                await bot.close()
                return

    asyncio.run(play())
    kinds = {type(e) for e in errors}
    assert kinds == {Rejected, FutureTick, StaleTick}, errors
    rejected = next(e for e in errors if isinstance(e, Rejected))
    assert rejected.code == "rejected" and "move_to" in rejected.message
    client.delete_match(match_id)


def test_refused_sockets_raise_their_error(client):
    url, token, match_id = fielder_match(client)
    with pytest.raises(Forbidden) as e:
        asyncio.run(Bot(url, "0" * 32).connect())
    assert e.value.status == 403
    with pytest.raises(NotFound):
        asyncio.run(Bot(client.play_url("no-such-match"), token).connect())
    client.delete_match(match_id)
    # An ended match: 410.
    deadline = time.monotonic() + 30
    realtime = client.create_match(
        {"sport": "baseball", "duration_s": 0.1, "agents": [{"id": "cf", "bot": True}]}
    )
    while client.get_match(realtime.id)["status"] != "ended":
        assert time.monotonic() < deadline
        time.sleep(0.05)
    with pytest.raises(Ended) as e:
        asyncio.run(Bot(client.play_url(realtime.id), realtime.bot_tokens["cf"]).connect())
    assert e.value.status == 410


def test_a_second_connection_replaces_the_first(client):
    url, token, match_id = fielder_match(client)

    async def play():
        first = Bot(url, token)
        iterator = first.__aiter__()
        p = await iterator.__anext__()
        await first.act(Stand(), p.tick)
        second = Bot(url, token)
        await second.connect()
        with pytest.raises(Replaced):
            while True:
                p = await iterator.__anext__()
                await first.act(Stand(), p.tick)
        await second.close()

    asyncio.run(play())
    client.delete_match(match_id)


def test_a_dropped_connection_reconnects_with_the_same_token(client):
    url, token, match_id = fielder_match(client)

    async def play():
        bot = Bot(url, token, backoff_s=0.05)
        dropped_at = None
        after = []
        async for p in bot:
            if dropped_at is None and p.tick >= 20:
                dropped_at = p.tick
                bot._socket.ws.transport.abort()  # the network fails under the bot
                continue
            if dropped_at is not None:
                after.append(p.tick)
                if len(after) == 5:
                    controllers = [a["controller"] for a in client.get_match(match_id)["agents"]]
                    await bot.close()
                    return bot, dropped_at, after, controllers
            await bot.act(Stand())

    bot, dropped_at, after, controllers = asyncio.run(play())
    assert bot.reconnections == 1
    assert after[0] > dropped_at and controllers == ["bot"]
    client.delete_match(match_id)


def test_basketball_perceptions_are_typed(client):
    created = client.create_match(
        {
            "sport": "basketball",
            "mode": "lockstep",
            "agents": [
                {"id": "o1", "team": "offense", "bot": True},
                {"id": "o2", "team": "offense", "strategy": "costmap"},
                {"id": "d1", "team": "defense", "strategy": "defense"},
            ],
            "options": {"possessions": 1},
        }
    )

    async def play():
        bot = Bot(client.play_url(created.id), created.bot_tokens["o1"])
        async for p in bot:
            await bot.close()
            return bot.hello, p

    hello, p = asyncio.run(play())
    assert hello.match.perception_every_ticks == 15
    assert [a.team for a in hello.match.agents] == ["offense", "offense", "defense"]
    assert isinstance(p.perception, PlayerPerception) and p.perception.self_id == "o1"
    assert {a.id for a in p.perception.agents} == {"o1", "o2", "d1"}
    assert p.tick % 15 == 0
    client.delete_match(created.id)
