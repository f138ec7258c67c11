"""Environment steps per second over loopback, and where the time goes.

    cargo build --release
    FIELDHOUSE_BIN=target/release/fieldhouse python clients/python/benchmarks/steps.py --runs 5

Starts its own server (``fieldhouse serve --no-demo`` on a free port) and measures, one
after the other:

* ``bot loop``: one fielder's bare protocol loop on :class:`fieldhouse.Socket` (a
  perception in, a command out, nothing else): the floor the environments stand on;
* ``gym fly ball, 1 fielder``: :class:`FieldhouseGymEnv` stepping one fielder through
  scripted balls (a step is a tick);
* ``pz fly ball, 2 fielders``: :class:`FieldhouseParallelEnv`, two fielders, the same
  balls (a step is a tick, both fielders acting);
* ``pz basketball, 2 bots``: ``o1`` and ``d1`` of the 2-v-1 (a step is 15 ticks, every
  agent acting once; the server plays the 14 between perceptions at once);
* ``4 × gym fly ball, vector``: four Gymnasium environments stepped in parallel by
  ``gymnasium.vector.AsyncVectorEnv`` (a process each) against the one server; a step
  of the vector is four environment steps, and the figure counts environment steps;
* ``4 × fly ball, one loop``: the same four in :class:`FieldhouseVectorEnv`, stepped
  together on one event loop in this process.

For each: steps per second (wall clock), and the CPU time per step of this process
(the client; for the vector, its worker processes are not in it) and of the server
process (from /proc), so a figure below target says whose time it is. Actions are
constant, so no policy's cost is counted. With ``--runs N`` each is measured N times,
one after the other, and the medians close the report.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import platform
import statistics
import time

import gymnasium
import numpy as np

from fieldhouse import LocalServer, Socket
from fieldhouse.env import (
    FieldhouseGymEnv,
    FieldhouseParallelEnv,
    basketball_scenario,
    fly_ball_scenario,
)
from fieldhouse.vector import FieldhouseVectorEnv

# Thirty flies to centre field, one after the other: an episode long enough that a reset
# (a match created and seated) does not enter the figure.
LAUNCHES = [
    {
        "time_s": 0.5 if i == 0 else 0.0,
        "speed_m_s": 30.0 + i % 10,
        "elevation_deg": 35.0 + i % 5 * 5,
        "azimuth_deg": 40.0 + i % 3 * 5,
    }
    for i in range(30)
]


def server_cpu_s(pid: int) -> float:
    """User plus system CPU seconds of process ``pid`` (Linux /proc)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class Meter:
    """Wall time and both processes' CPU time over a stretch of steps."""

    def __init__(self, pid: int):
        self.pid = pid

    def __enter__(self):
        self.wall, self.client, self.server = (
            time.perf_counter(),
            time.process_time(),
            server_cpu_s(self.pid),
        )
        return self

    def __exit__(self, *exc):
        self.wall = time.perf_counter() - self.wall
        self.client = time.process_time() - self.client
        self.server = server_cpu_s(self.pid) - self.server

    def row(self, name: str, steps: int) -> str:
        us = 1e6 / steps
        return (
            f"{name:<26} {steps:>6} steps {steps / self.wall:>8.0f} steps/s   per step: "
            f"wall {self.wall * us:>7.0f} µs, client CPU {self.client * us:>6.0f} µs, "
            f"server CPU {self.server * us:>6.0f} µs"
        )


def bot_loop(server: LocalServer, steps: int) -> str:
    client = server.client()
    scenario = fly_ball_scenario(launches=LAUNCHES)
    scenario["mode"] = "lockstep"
    created = client.create_match(scenario)

    async def play() -> int:
        socket = await Socket.open(client.play_url(created.id), created.bot_tokens["f0"])
        done = 0
        while done < steps:
            message = await socket.recv()
            if message["type"] == "perception":
                await socket.send_text(
                    '{"type":"command","tick":%d,"action":{"kind":"stand"}}' % message["tick"]
                )
                done += 1
            elif message["type"] == "end":
                break
        await socket.close()
        return done

    with Meter(server.pid) as m:
        done = asyncio.run(play())
    client.delete_match(created.id)
    return m.row("bot loop (no env)", done)


def run_env(server: LocalServer, name: str, scenario: dict, steps: int, action) -> str:
    env = FieldhouseParallelEnv(server.url, scenario, admin_token=server.admin_token)
    env.reset(seed=1)
    done = 0
    with Meter(server.pid) as m:
        while env.agents and done < steps:
            env.step({a: action for a in env.agents})
            done += 1
    env.close()
    return m.row(name, done)


def run_gym(server: LocalServer, name: str, steps: int) -> str:
    env = FieldhouseGymEnv(
        server.url, fly_ball_scenario(launches=LAUNCHES), admin_token=server.admin_token
    )
    env.reset(seed=1)
    action = np.zeros(2, np.float32)
    done = 0
    with Meter(server.pid) as m:
        while done < steps:
            _, _, terminated, truncated, _ = env.step(action)
            done += 1
            if terminated or truncated:
                env.reset()
    env.close()
    return m.row(name, done)


def run_vector(server: LocalServer, name: str, envs: int, steps: int) -> str:
    """``envs`` Gymnasium environments in worker processes, ``steps`` vector steps."""
    url, token = server.url, server.admin_token
    make = [
        lambda: FieldhouseGymEnv(url, fly_ball_scenario(launches=LAUNCHES), admin_token=token)
        for _ in range(envs)
    ]
    return time_vector(server, name, gymnasium.vector.AsyncVectorEnv(make), steps)


def run_one_loop(server: LocalServer, name: str, envs: int, steps: int) -> str:
    """``envs`` environments on one event loop, ``steps`` vector steps."""
    scenario = fly_ball_scenario(launches=LAUNCHES)
    vector = FieldhouseVectorEnv(envs, server.url, scenario, admin_token=server.admin_token)
    return time_vector(server, name, vector, steps)


def time_vector(server: LocalServer, name: str, vector, steps: int) -> str:
    """``steps`` steps of a vector of fly-ball environments standing still, counted as
    environment steps; the vector is closed after."""
    vector.reset(seed=1)
    actions = np.zeros((vector.num_envs, 2), np.float32)
    with Meter(server.pid) as m:
        for _ in range(steps):
            vector.step(actions)
    vector.close()
    return m.row(name, steps * vector.num_envs)


def median_rows(rows: list[str]) -> str:
    """The median steps/s of each measurement's rows."""
    rates: dict[str, list[float]] = {}
    for row in rows:
        name, rest = row[:26].strip(), row[26:].split()
        rates.setdefault(name, []).append(float(rest[2]))
    return "\n".join(
        f"{name:<26} median {statistics.median(r):>8.0f} steps/s   runs: "
        + ", ".join(f"{x:.0f}" for x in r)
        for name, r in rates.items()
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", help="the server binary (default $FIELDHOUSE_BIN)")
    parser.add_argument("--steps", type=int, default=5000, help="fly-ball steps (default 5000)")
    parser.add_argument(
        "--basketball-steps", type=int, default=1500, help="basketball steps (default 1500)"
    )
    parser.add_argument("--runs", type=int, default=1, help="measure each this many times")
    args = parser.parse_args()
    rows = []
    with LocalServer(args.bin) as server:
        print(
            f"server {server.binary}; Python {platform.python_version()} on {platform.machine()}, "
            f"{os.cpu_count()} CPUs"
        )
        for _ in range(args.runs):
            measured = [
                bot_loop(server, args.steps),
                run_gym(server, "gym fly ball, 1 fielder", args.steps),
                run_env(
                    server,
                    "pz fly ball, 2 fielders",
                    fly_ball_scenario(fielders=2, launches=LAUNCHES),
                    args.steps,
                    np.zeros(2, np.float32),
                ),
                run_env(
                    server,
                    "pz basketball, 2 bots",
                    basketball_scenario(possessions=200),
                    args.basketball_steps,
                    0,
                ),
                run_vector(server, "4 × gym fly ball, vector", 4, args.steps // 4),
                run_one_loop(server, "4 × fly ball, one loop", 4, args.steps // 4),
            ]
            for row in measured:
                print(row, flush=True)
            rows += measured
    if args.runs > 1:
        print(median_rows(rows))


if __name__ == "__main__":
    main()
