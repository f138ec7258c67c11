"""The Chapman example against the built-in ``chapman`` strategy on the same scripted
balls: the Python bot, which sees only its perception's optical variables, must catch at
least what the server's own strategy catches, less a margin of MARGIN balls (its rates
are one-tick differences where the built-in reads its own sighting history)."""

from __future__ import annotations

import asyncio
import random
import time

from .conftest import load_example

BALLS = 16
MARGIN = 1


def launches(seed: int = 24) -> list[dict]:
    """Flies around a fielder 80 m out in centre field: short, deep, to either side, with
    and without backspin; every one of them hit as soon as the previous one is dead."""
    rng = random.Random(seed)
    return [
        {
            "time_s": 0.5 if i == 0 else 0.0,
            "speed_m_s": round(rng.uniform(28.0, 44.0), 2),
            "elevation_deg": round(rng.uniform(25.0, 60.0), 2),
            "azimuth_deg": round(rng.uniform(33.0, 57.0), 2),
            "spin_rpm": round(rng.uniform(0.0, 2500.0), 1),
        }
        for i in range(BALLS)
    ]


def test_python_chapman_catches_what_the_built_in_catches(client):
    chapman = load_example("chapman_bot")
    balls = launches()

    built_in = chapman.scenario(balls)
    built_in["mode"] = "fast"
    built_in["agents"] = [{"id": "chapman", "strategy": "chapman", "position": chapman.HOME}]
    created = client.create_match(built_in)
    deadline = time.monotonic() + 60
    while (m := client.get_match(created.id))["status"] != "ended":
        assert time.monotonic() < deadline
        time.sleep(0.05)
    reference = m["score"]

    bot = client.create_match(chapman.scenario(balls))
    result = asyncio.run(chapman.play(client.play_url(bot.id), bot.bot_tokens["chapman"]))

    print(f"built-in chapman {reference}, Python chapman {result}")
    assert reference["balls"] == result["balls"] == BALLS
    assert result["caught"] >= reference["caught"] - MARGIN, (result, reference)
