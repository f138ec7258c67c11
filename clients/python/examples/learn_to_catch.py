"""Learning to catch: an evolution strategy trains a fielder from what it sees, then meets
Chapman's and McBeath's fielders on balls it never trained on.

    cargo build --release   # then, from the repository's root:
    export FIELDHOUSE_BIN=target/release/fieldhouse
    python clients/python/examples/learn_to_catch.py --minutes 10

The script starts its own server (``fieldhouse serve``, recording into a temporary
directory) and needs the ``env`` extra (numpy, gymnasium). It prints how training went,
then a table: catches on held-out balls, for the learned fielder and for the server's
built-in ``chapman`` and ``lot-optical`` on the very same balls, and each one's path
signatures (docs/catching.md), measured from the recorded frames by ``fieldhouse replay
paths``, one code path for all three.

**What the fielder sees.** Only the optical variables of its perception and its own
motion: tan ψ (the ball's elevation), its rate and its change (the optical
acceleration), the bearing's rate dα/dt, and its own velocity along and across the line
of sight. Not the distance to the ball (the built-in strategies use it to scale their
gains; people beyond about 30 m barely perceive it) and never where the ball lands.

**The policy** is linear in those features, in the frame of the line of sight: one
row of weights for the acceleration toward the ball, one for the acceleration across
it, each squashed by tanh to the body's maximum. It stands still for the first 0.3 s
of a flight, the built-in strategies' reaction time. Fourteen numbers in all: any law
of the form "accelerate in proportion to these" is one of them, OAC's (radial
acceleration against the optical acceleration) and Chapman's lateral law (sideways
against dα/dt) included, and so are many that catch nothing.

**Training** is an evolution strategy (Salimans et al. 2017): each generation draws
fresh balls, plays ``population`` perturbed copies of the weights on them (antithetic
pairs, each copy its own lock-step match, all stepped together by a
:class:`~fieldhouse.vector.FieldhouseVectorEnv`) and moves the weights along the
perturbations in proportion to their centred ranks. A copy's score is its catches, plus
half a catch times exp(−miss / 10 m) for each ball it missed, the miss being the
distance it last perceived to the ball: a gradient toward the ball before the first
catch. The balls are fly balls toward a centre fielder 80 m out: 26–42 m/s, 25–65°
up, 25–65° of azimuth, 1000–3000 rpm of backspin; some fall out of anyone's reach.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import subprocess
import tempfile
import time
from dataclasses import dataclass

import numpy as np
from gymnasium.vector import AutoresetMode

from fieldhouse import LocalServer
from fieldhouse.env import FIELDER_OBSERVATION, fly_ball_scenario
from fieldhouse.vector import FieldhouseVectorEnv

TICK_HZ = 60.0
REACTION_S = 0.3  # the built-in strategies' first step comes 0.3 s after the hit
FIRST_LAUNCH_S = 1.0  # time for the bots to be seated before the first ball
PAUSE_S = 0.5
HOME = fly_ball_scenario()["agents"][0]["position"]  # centre field, 80 m out

# The features, each divided by a typical size so that weights near 1 matter.
FEATURES = (
    "d_tan_psi_dt",
    "optical_acceleration",
    "tan_psi",
    "d_alpha_dt",
    "v_toward",
    "v_across",
    "bias",
)
FEATURE_SCALE = np.array([0.5, 0.5, 1.0, 0.1, 8.5, 8.5, 1.0])
OUTPUTS = ("toward", "across")
OBS = {name: i for i, name in enumerate(FIELDER_OBSERVATION)}


def draw_launches(rng: np.random.Generator, n: int) -> list[dict]:
    """``n`` fly balls toward centre field, the first hit at 1 s, each next one
    ``PAUSE_S`` after the one before is dead."""
    return [
        {
            "time_s": FIRST_LAUNCH_S if i == 0 else 0.0,
            "speed_m_s": round(float(rng.uniform(26.0, 42.0)), 3),
            "elevation_deg": round(float(rng.uniform(25.0, 65.0)), 3),
            "azimuth_deg": round(float(rng.uniform(25.0, 65.0)), 3),
            "spin_rpm": round(float(rng.uniform(1000.0, 3000.0)), 1),
        }
        for i in range(n)
    ]


def scenario(launches: list[dict]) -> dict:
    """One bot fielder in centre field and the balls."""
    s = fly_ball_scenario(1, launches)
    s["options"]["pause_s"] = PAUSE_S
    return s


class Policy:
    """The linear policy of the module's docstring, for ``n`` fielders at once (one
    weight matrix each): it keeps each one's last d(tan ψ)/dt for the optical
    acceleration."""

    def __init__(self, n: int):
        self.last_rate = np.full(n, np.nan)

    def features(self, obs: np.ndarray) -> np.ndarray:
        """The scaled features, ``(n, len(FEATURES))``, of observations ``(n, 13)``."""
        in_play = obs[:, OBS["ball_in_play"]] > 0.5
        rate = obs[:, OBS["d_tan_psi_dt"]]
        # The first tick of a ball has no rate yet, the second none to difference.
        fresh = ~in_play | (obs[:, OBS["t"]] < 1.5 / TICK_HZ)
        acceleration = np.where(np.isnan(self.last_rate), 0.0, (rate - self.last_rate) * TICK_HZ)
        self.last_rate = np.where(fresh, np.nan, rate)
        alpha = obs[:, OBS["alpha"]]
        toward = np.stack([np.cos(alpha), np.sin(alpha)], axis=1)
        velocity = obs[:, [OBS["vx"], OBS["vz"]]]
        raw = np.stack(
            [
                rate,
                np.where(fresh, 0.0, acceleration),
                obs[:, OBS["tan_psi"]],
                obs[:, OBS["d_alpha_dt"]],
                (velocity * toward).sum(axis=1),
                velocity[:, 1] * toward[:, 0] - velocity[:, 0] * toward[:, 1],
                np.ones(len(obs)),
            ],
            axis=1,
        )
        # A ball nearly overhead sends tan ψ and its rates off to infinity.
        return np.clip(raw / FEATURE_SCALE, -5.0, 5.0)

    def act(self, weights: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """Accelerations ``[ax, az]`` in units of the body's maximum, ``(n, 2)``, for
        weights ``(n, 2, len(FEATURES))``."""
        phi = self.features(obs)
        along, across = np.tanh(np.einsum("nof,nf->on", weights, phi))
        alpha = obs[:, OBS["alpha"]]
        c, s = np.cos(alpha), np.sin(alpha)
        a = np.stack([along * c - across * s, along * s + across * c], axis=1)
        a /= np.maximum(1.0, np.linalg.norm(a, axis=1))[:, None]
        waiting = (obs[:, OBS["ball_in_play"]] < 0.5) | (obs[:, OBS["t"]] < REACTION_S)
        a[waiting] = 0.0
        return a.astype(np.float32)


@dataclass
class Outcomes:
    """Each fielder's balls: caught or not, and the distance it last saw to each."""

    caught: np.ndarray  # (n, balls) bool
    miss_m: np.ndarray  # (n, balls)

    def score(self) -> np.ndarray:
        """Catches, and half a catch times exp(-miss / 10 m) for each ball missed."""
        near = 0.5 * np.exp(-np.nan_to_num(self.miss_m, nan=1e3) / 10.0)
        return np.where(self.caught, 1.0, near).sum(axis=1)


def play(venv: FieldhouseVectorEnv, weights: np.ndarray, launches: list[dict]) -> Outcomes:
    """Each environment's fielder plays ``launches`` with its own weights, all episodes
    stepped together until the last ends (``venv`` must not autoreset)."""
    n, balls = venv.num_envs, len(launches)
    obs, _ = venv.reset(options={"scenario_options": {"launches": launches}})
    policy = Policy(n)
    caught = np.zeros((n, balls), bool)
    miss = np.full((n, balls), np.nan)
    ball = np.zeros(n, int)  # the ball each fielder is on
    done = np.zeros(n, bool)
    while not done.all():
        actions = policy.act(weights, obs)
        in_play = obs[:, OBS["ball_in_play"]] > 0.5
        distance = obs[:, OBS["distance_m"]]
        obs, rewards, terminated, truncated, _ = venv.step(actions)
        # The match's end is perceived as no perception: its last ball is over too.
        now_in_play = (obs[:, OBS["ball_in_play"]] > 0.5) & ~(terminated | truncated)
        for i in np.flatnonzero(~done):
            k = min(ball[i], balls - 1)
            if in_play[i]:
                miss[i, k] = distance[i]
            caught[i, k] |= rewards[i] > 0
            if in_play[i] and not now_in_play[i]:
                ball[i] += 1
        done |= terminated | truncated
    return Outcomes(caught, miss)


@dataclass
class Training:
    """The weights found, and each generation's mean catch rate and score."""

    weights: np.ndarray
    start: np.ndarray
    history: list[dict]
    seconds: float


def train(
    url: str,
    admin_token: str,
    *,
    seed: int = 0,
    generations: int = 200,
    population: int = 16,
    balls: int = 6,
    sigma: float = 0.3,
    learning_rate: float = 0.1,
    minutes: float = 15.0,
    without: tuple[str, ...] = (),
    log=print,
) -> Training:
    """Evolution strategy over :class:`Policy`'s weights from a random start (normal,
    0.5); stops after ``generations`` or ``minutes``, whichever is first. The features
    named in ``without`` keep weight 0 throughout: an ablation."""
    unknown = set(without) - set(FEATURES)
    if unknown:
        raise ValueError(f"no features {sorted(unknown)}; the features are {FEATURES}")
    rng = np.random.default_rng(seed)
    shape = (len(OUTPUTS), len(FEATURES))
    used = np.array([f not in without for f in FEATURES], float)
    start = rng.normal(0.0, 0.5, shape) * used
    weights = start.copy()
    pairs = population // 2
    m, v = np.zeros(shape), np.zeros(shape)  # Adam's moments
    history = []
    began = time.perf_counter()
    venv = FieldhouseVectorEnv(
        2 * pairs,
        url,
        scenario(draw_launches(rng, balls)),
        admin_token=admin_token,
        autoreset_mode=AutoresetMode.DISABLED,
    )
    try:
        for g in range(generations):
            if time.perf_counter() - began > 60.0 * minutes:
                break
            eps = rng.normal(size=(pairs, *shape)) * used
            candidates = np.concatenate([weights + sigma * eps, weights - sigma * eps])
            outcomes = play(venv, candidates, draw_launches(rng, balls))
            score = outcomes.score()
            # Centred ranks: only the order of the scores counts, not their scale.
            ranks = np.empty(len(score))
            ranks[np.argsort(score)] = np.arange(len(score))
            centred = ranks / (len(score) - 1) - 0.5
            gradient = np.einsum("p,pof->of", centred[:pairs] - centred[pairs:], eps) / (
                2 * pairs * sigma
            )
            m = 0.9 * m + 0.1 * gradient
            v = 0.999 * v + 0.001 * gradient**2
            step = m / (1 - 0.9 ** (g + 1)) / (np.sqrt(v / (1 - 0.999 ** (g + 1))) + 1e-8)
            weights = weights + learning_rate * step
            row = {
                "generation": g + 1,
                "catch_rate": float(outcomes.caught.mean()),
                "score": float(score.mean()),
                "seconds": time.perf_counter() - began,
            }
            history.append(row)
            log(
                f"generation {g + 1:3d}: caught {100 * row['catch_rate']:5.1f}% of "
                f"{population}x{balls} balls, score {row['score']:.2f} ({row['seconds']:.0f} s)"
            )
    finally:
        venv.close()
    return Training(weights, start, history, time.perf_counter() - began)


def evaluate_learned(
    url: str,
    admin_token: str,
    replay_dir: pathlib.Path,
    weights: np.ndarray,
    seeds: list[int],
    balls: int,
) -> list[pathlib.Path]:
    """Plays ``weights`` on each seed's balls (one recorded match per seed, all stepped
    together); returns the replay files."""
    venv = FieldhouseVectorEnv(
        len(seeds),
        url,
        scenario(draw_launches(np.random.default_rng(seeds[0]), balls)),
        admin_token=admin_token,
        autoreset_mode=AutoresetMode.DISABLED,
        record=True,
        name="learned fielder",
    )
    client = venv.envs[0].client
    files = []
    try:
        # One seed's balls per environment: reset each on its own.
        for i, s in enumerate(seeds):
            mask = np.arange(len(seeds)) == i
            balls_of_seed = {"launches": draw_launches(np.random.default_rng(s), balls)}
            options = {"reset_mask": mask, "scenario_options": balls_of_seed}
            obs, _ = venv.reset(seed=s, options=options)
        policy = Policy(len(seeds))
        stacked = np.repeat(weights[None], len(seeds), axis=0)
        done = np.zeros(len(seeds), bool)
        while not done.all():
            obs, _, terminated, truncated, _ = venv.step(policy.act(stacked, obs))
            done |= terminated | truncated
        for env in venv.envs:
            replay = client.get_match(env.match_id)["replay"]
            files.append(replay_dir / f"{replay}.jsonl.zst")
    finally:
        venv.close()
    return files


def run_builtin(binary: str, strategy: str, seed: int, balls: int, out: pathlib.Path) -> None:
    """``fieldhouse run`` of the same balls with a built-in fielder, every tick recorded."""
    s = scenario(draw_launches(np.random.default_rng(seed), balls))
    s["agents"] = [{"id": "f0", "strategy": strategy, "position": HOME}]
    s.update(seed=seed, frame_hz=TICK_HZ)
    toml = out.with_suffix(".toml")
    toml.write_text("".join(f"{key} = {_toml(value)}\n" for key, value in s.items()))
    subprocess.run(
        [binary, "run", str(toml), "--out", str(out)], check=True, capture_output=True, text=True
    )


def _toml(value) -> str:
    """A value as TOML (inline tables and arrays; strings and numbers as JSON writes them,
    which TOML reads the same)."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return json.dumps(value)


def measure(binary: str, replay: pathlib.Path, wait_s: float = 10.0) -> list[dict]:
    """Every run of ``fieldhouse replay paths`` on the file, waiting for the recorder to
    finish it (its footer is written as the match ends)."""
    deadline = time.monotonic() + wait_s
    while True:
        info = subprocess.run(
            [binary, "replay", "info", str(replay), "--json"], capture_output=True, text=True
        )
        if info.returncode == 0 and json.loads(info.stdout)["complete"]:
            break
        if time.monotonic() > deadline:
            raise RuntimeError(f"{replay} did not complete: {info.stdout}{info.stderr}")
        time.sleep(0.1)
    paths = subprocess.run(
        [binary, "replay", "paths", str(replay), "--json"],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(paths.stdout)["runs"]


def summary(runs: list[dict]) -> dict:
    """Catches and median signatures over runs (``replay paths``' per-ball rows)."""

    def median(key):
        xs = [r[key] for r in runs if r[key] is not None]
        return float(np.median(xs)) if xs else math.nan

    shapes = [r["shape"] for r in runs]
    return {
        "balls": len(runs),
        "caught": sum(r["caught"] for r in runs),
        "away_from_home": shapes.count("bulges_away_from_home") / max(1, len(runs)),
        "bulge": median("bulge"),
        "rate_drift": median("rate_drift"),
        "bearing_sweep_deg": median("bearing_sweep_deg"),
        "image_bend": median("image_bend"),
    }


def save_weights(path: pathlib.Path, weights: np.ndarray) -> None:
    """The weights as JSON, each row a mapping from feature to weight."""
    rows = {
        o: dict(zip(FEATURES, map(float, row), strict=True))
        for o, row in zip(OUTPUTS, weights, strict=True)
    }
    path.write_text(json.dumps(rows, indent=1) + "\n")


def load_weights(path: pathlib.Path) -> np.ndarray:
    """Weights that :func:`save_weights` wrote (a feature left out weighs 0)."""
    rows = json.loads(path.read_text())
    unknown = {f for row in rows.values() for f in row} - set(FEATURES)
    if set(rows) != set(OUTPUTS) or unknown:
        raise ValueError(
            f"{path}: rows {sorted(rows)} (want {OUTPUTS}), unknown features {unknown}"
        )
    return np.array([[rows[o].get(f, 0.0) for f in FEATURES] for o in OUTPUTS])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=15.0, help="training time at most")
    parser.add_argument("--generations", type=int, default=1000)
    parser.add_argument("--population", type=int, default=16)
    parser.add_argument("--balls", type=int, default=6, help="balls per generation")
    parser.add_argument("--seed", type=int, default=0, help="training's seed")
    parser.add_argument(
        "--without",
        default="",
        help=f"features to leave out, comma-separated (an ablation): {', '.join(FEATURES)}",
    )
    parser.add_argument(
        "--eval-seeds",
        default="101,102,103",
        help="held-out seeds, comma-separated: each draws --eval-balls balls",
    )
    parser.add_argument("--eval-balls", type=int, default=100)
    parser.add_argument("--save", help="write the trained weights to this JSON file")
    parser.add_argument(
        "--load", help="evaluate the weights in this JSON file (from --save) without training"
    )
    parser.add_argument("--fieldhouse", help="the binary (default: $FIELDHOUSE_BIN, PATH)")
    args = parser.parse_args()
    seeds = [int(s) for s in args.eval_seeds.split(",")]
    without = tuple(f for f in args.without.split(",") if f)

    with (
        tempfile.TemporaryDirectory() as tmp,
        LocalServer(args.fieldhouse, args=["--replay-dir", tmp]) as server,
    ):
        tmp_dir = pathlib.Path(tmp)
        if args.load:
            weights = load_weights(pathlib.Path(args.load))
        else:
            trained = train(
                server.url,
                server.admin_token,
                seed=args.seed,
                generations=args.generations,
                population=args.population,
                balls=args.balls,
                minutes=args.minutes,
                without=without,
            )
            weights = trained.weights
            print(f"\ntrained {len(trained.history)} generations in {trained.seconds:.0f} s")
            if args.save:
                save_weights(pathlib.Path(args.save), weights)
        print("weights (rows: acceleration toward / across the line of sight):")
        print("          " + " ".join(f"{f:>20}" for f in FEATURES))
        for name, row in zip(OUTPUTS, weights, strict=True):
            print(f"{name:>8}  " + " ".join(f"{w:20.2f}" for w in row))

        learned = evaluate_learned(
            server.url, server.admin_token, tmp_dir, weights, seeds, args.eval_balls
        )
        rows = {"learned": [r for f in learned for r in measure(server.binary, f)]}
        for strategy in ("chapman", "lot-optical"):
            rows[strategy] = []
            for s in seeds:
                out = tmp_dir / f"{strategy}-{s}.jsonl"
                run_builtin(server.binary, strategy, s, args.eval_balls, out)
                rows[strategy] += measure(server.binary, out)
    table = {name: summary(runs) for name, runs in rows.items()}
    chapman = table["chapman"]["caught"]
    pairs = list(zip(rows["learned"], rows["chapman"], strict=True))
    both = sum(a["caught"] and b["caught"] for a, b in pairs)
    print(f"\nheld-out seeds {seeds}, {args.eval_balls} balls each")
    print("fielder       caught  of chapman's  ←home  bulge  ṙ drift  α sweep  img bend")
    for name, t in table.items():
        print(
            f"{name:<12} {t['caught']:4d}/{t['balls']:<4d} "
            f"{100 * t['caught'] / max(1, chapman):9.1f}%  {100 * t['away_from_home']:4.0f}% "
            f"{t['bulge']:+6.2f} {t['rate_drift']:8.3f} {t['bearing_sweep_deg']:7.1f}° "
            f"{t['image_bend']:9.3f}"
        )
    print(
        f"balls both caught: {both}; the learned fielder's alone: "
        f"{table['learned']['caught'] - both}; chapman's alone: {chapman - both}"
    )


if __name__ == "__main__":
    main()
