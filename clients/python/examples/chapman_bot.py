"""A fielder bot that catches fly balls with Chapman's (1968) optical acceleration
cancellation, from the optical variables of its perception only: tan ψ (the tangent of
the ball's elevation above the eye), its rate, the bearing α and its rate, and the ground
distance that scales the gains. It never sees where the ball is going to land.

Chapman's observation: a fielder who keeps the image of the ball rising at a constant
rate (d²tan ψ/dt² = 0) arrives where the ball comes down. The bot holds d(tan ψ)/dt at
the rate it saw when it started running (Dienes & McLeod: any constant rate works),
accelerating away from the batter when the image speeds up (the ball will carry over) and
toward it when it slows (the ball drops short); sideways it cancels the bearing's drift
dα/dt (Tresilian's lateral term). The same law, gains and 0.3 s reaction time as the
server's built-in ``chapman`` strategy (crates/core/src/fielding/strategy/chapman.rs).

Run it against a server (``fieldhouse serve``) in one of two ways:

    # Create a lock-step match of scripted balls (needs FIELDHOUSE_ADMIN_TOKEN) and play it:
    python chapman_bot.py --server http://127.0.0.1:7878
    # Or play an agent of a match someone else created with "bot": true:
    python chapman_bot.py --play ws://127.0.0.1:7878/ws/matches/ID/play --token TOKEN
"""

from __future__ import annotations

import argparse
import asyncio
import math

from fieldhouse import Accelerate, Bot, Client, Perception, Stand
from fieldhouse.messages import Optics

# Gain of the radial law, 1/s: the optical rate returns to its reference in about 1/3 s.
RATE_GAIN = 3.0
# Gain of the lateral law, 1/s: the sideways drift across the line of sight is matched in 0.2 s.
LATERAL_GAIN = 5.0
# Below about 3 degrees of elevation the angles mostly show the launch height: wait.
CLEARLY_ABOVE_EYE_TAN_PSI = 0.05
# A person's time from the crack of the bat to the first step.
REACTION_S = 0.3

# Balls for --server: toward the fielder's home (80 m out at azimuth 45), short, deep, wide.
LAUNCHES = [
    {"time_s": 0.5, "speed_m_s": 36.0, "elevation_deg": 40.0, "azimuth_deg": 45.0},
    {
        "time_s": 0.0,
        "speed_m_s": 33.0,
        "elevation_deg": 50.0,
        "azimuth_deg": 42.0,
        "spin_rpm": 1500.0,
    },
    {
        "time_s": 0.0,
        "speed_m_s": 40.0,
        "elevation_deg": 35.0,
        "azimuth_deg": 50.0,
        "spin_rpm": 2000.0,
    },
    {
        "time_s": 0.0,
        "speed_m_s": 38.0,
        "elevation_deg": 30.0,
        "azimuth_deg": 38.0,
        "spin_rpm": 2500.0,
    },
]
HOME = [56.569, 56.569]


class Chapman:
    """Chapman's law with Tresilian's lateral term; one instance per fielder."""

    def __init__(self, reaction_s: float = REACTION_S):
        self.reaction_s = reaction_s
        self.rate_ref: float | None = None

    def act(self, perception: Perception) -> Accelerate | Stand:
        """The command answering a fielder's perception."""
        accel = self.accelerate(perception.perception.optics)
        return Stand() if accel is None else Accelerate(accel)

    def accelerate(self, o: Optics | None) -> tuple[float, float] | None:
        """The acceleration ``[ax, az]`` (m/s², before the body clips it) for what the eye
        sees; None between balls (stop: the next launch puts the fielder back home)."""
        if o is None:
            self.rate_ref = None
            return None
        if o.t < self.reaction_s or o.rates is None or o.tan_psi < CLEARLY_ABOVE_EYE_TAN_PSI:
            return (0.0, 0.0)
        rate = o.rates.d_tan_psi_dt
        if self.rate_ref is None:
            self.rate_ref = rate
        d = o.distance_m
        # Radial: oppose the optical acceleration accumulated since the reference; the
        # factor d / tan ψ makes the loop's time constant the same at every distance.
        radial = -RATE_GAIN * (d / o.tan_psi) * (rate - self.rate_ref)
        # Lateral: the ball's sideways speed across the line of sight is d · dα/dt.
        lateral = LATERAL_GAIN * d * o.rates.d_alpha_dt
        c, s = math.cos(o.alpha), math.sin(o.alpha)
        # Toward the ball is (c, s); a quarter turn toward increasing α is (-s, c).
        return (radial * c - lateral * s, radial * s + lateral * c)


async def play(url: str, token: str) -> dict | None:
    """Plays the agent to the match's end; returns the final score."""
    fielder = Chapman()
    bot = Bot(url, token, on_perception=fielder.act)
    end = await bot.run()
    return end.result if end else None


def scenario(launches: list[dict] = LAUNCHES, home: list[float] = HOME) -> dict:
    """A lock-step match of one bot fielder at ``home`` and the scripted ``launches``."""
    return {
        "sport": "baseball",
        "mode": "lockstep",
        "agents": [{"id": "chapman", "bot": True, "position": home}],
        "options": {"pause_s": 0.5, "launches": launches},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--server", help="create a match on this server (http://HOST:PORT)")
    parser.add_argument("--play", help="a bot URL, ws://HOST:PORT/ws/matches/ID/play")
    parser.add_argument("--token", help="the agent's bot token (with --play)")
    args = parser.parse_args()
    if args.server:
        client = Client(args.server)
        match = client.create_match(scenario())
        url, token = client.play_url(match.id), match.bot_tokens["chapman"]
    elif args.play and args.token:
        url, token = args.play, args.token
    else:
        parser.error("give --server URL, or --play URL and --token TOKEN")
    print("final score:", asyncio.run(play(url, token)))


if __name__ == "__main__":
    main()
