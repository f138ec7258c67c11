//! An independent check of the `chapman` fielder: a second, small simulator
//! written from docs/catching.md flies the same launches as the real `fieldhouse catch`,
//! and the two must catch the same balls.
//!
//! **What is independent.** Everything below the constants: the ball's flight (textbook
//! RK4 on a six-number state at four steps a tick, the landing by linear interpolation of
//! the step that crosses the ground; the library steps once a tick and interpolates a
//! Hermite cubic), the eye, Chapman's law with Tresilian's lateral term, the body and the
//! catch zone. They are plain arrays and one function per stage, written from the
//! documentation, not from the library's code; nothing here uses a `fieldhouse` type.
//! The launches are this file's own draws (its own generator and flight place the
//! fielder), not `catch-sweep`'s. The binary runs as a user runs it, once per launch.
//!
//! **What is shared.** Only what docs/catching.md states: Nathan's drag and lift laws and
//! the baseball's constants; the eye height and what the eye reads (tan ψ and α, and
//! their rates: the ideal observer, no delay and no noise, sees them as they are; the
//! human observer without its judgement errors fits them over its window, carries them
//! and the distance cue over its delay, takes out its own movement, and finishes the
//! catch with a lunge); the
//! law a1 = −K·(d/tan ψ)·(ṙ − ṙ₀), a2 = K_lat·d·α̇ with K = 3/s, K_lat = 5/s and ṙ₀ the
//! rate at the first step, once the ball is clearly above the eye (tan ψ ≥ 0.05); the
//! human limits and how the body clips them; the catch zone. Where the documentation
//! leaves a choice open, the comment at that line says which reading the oracle takes.
//!
//! **Why ±3 percentage points** (the bound on the two catch rates). Two faithful
//! implementations differ in rounding, integration and how the eye estimates rates,
//! which move a fielder by centimetres and so flip only a ball that passes within
//! centimetres of the edge of the reach; a few such balls in a few hundred are well
//! inside 3 points, while a wrong law is not: without the lateral term chapman catches a
//! thirtieth as many balls. The rate is a blunt instrument, though: chapman catches
//! nearly the same balls with its gains 10 % off, or even without the d/tan ψ factor. So
//! the test also compares the fielders' paths tick by tick, which such errors move by
//! decimetres to metres.

use crate::common;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{PI, TAU};

// The documented constants (docs/catching.md), in SI units.
const GRAVITY: f64 = 9.81;
const AIR_DENSITY: f64 = 1.194;
const BALL_MASS: f64 = 0.145;
const BALL_CIRCUMFERENCE: f64 = 9.125 * 0.0254;
const LAUNCH_HEIGHT: f64 = 1.0;
const TICK_HZ: f64 = 60.0;
const EYE_HEIGHT: f64 = 1.7;
const TOP_SPEED: f64 = 8.5;
const TOP_ACCEL: f64 = 4.5;
const REACTION_S: f64 = 0.3;
/// Chapman's radial gain K and Tresilian's lateral gain K_lat, per second.
const RADIAL_GAIN: f64 = 3.0;
const LATERAL_GAIN: f64 = 5.0;
/// tan ψ from which the ball counts as clearly above the eye.
const CLEARLY_ABOVE: f64 = 0.05;
const REACH: f64 = 1.0;
const CATCH_BAND: (f64, f64) = (0.3, 2.4);

/// The human observer's settings with its judgement errors switched off (they are random,
/// and two implementations cannot draw the same numbers): what remains of its senses is
/// the delay, the window of the fits, the distance cue's range, and the finishing phase
/// with its lunge and reach (docs/catching.md, "Observers").
const HUMAN_DELAY_S: f64 = 0.2;
const HUMAN_WINDOW_S: f64 = 0.1;
const HUMAN_CUE_RANGE: f64 = 30.0;
const HUMAN_FINISH_S: f64 = 0.5;
const HUMAN_REACH: f64 = 0.9;
const HUMAN_LUNGE: f64 = 0.6;
const HUMAN_FLAGS: &str = "--observer human --rate-weber 0 --direction-deg 0 --distance-weber 0";

/// The oracle's ball-flight steps per tick: its flight is not the library's
/// one-step-a-tick sequence of numbers, and a finer step only makes it more exact.
const SUBSTEPS: usize = 4;

/// One fly ball and where the fielder starts.
struct Launch {
    speed: f64,
    elevation_deg: f64,
    azimuth_deg: f64,
    spin_rpm: f64,
    fielder: [f64; 2],
}

/// The ball's state at each tick from the launch until the first tick below the ground,
/// and the point (x, z) where it first reaches the ground.
struct Flight {
    at_ticks: Vec<BallState>,
    landing: [f64; 2],
}

/// Position then velocity: x, y, z, vx, vy, vz.
type BallState = [f64; 6];

/// The time derivative of the ball's state in Nathan's air: gravity, drag ½ρA·Cd·|v|·v
/// and Magnus lift ½ρA·CL·|v|² along ω̂ × v̂, the forces divided by the mass.
fn ball_derivative(state: &BallState, spin_axis: [f64; 3], spin_rpm: f64) -> BallState {
    let v = [state[3], state[4], state[5]];
    let radius = BALL_CIRCUMFERENCE / TAU;
    let k = 0.5 * AIR_DENSITY * PI * radius * radius / BALL_MASS;
    let speed = length3(v);
    let cd = 0.3008 + 0.0292 * spin_rpm / 1000.0;
    let s = radius * (spin_rpm * TAU / 60.0) / speed;
    let cl = 1.120 * s / (0.583 + 2.333 * s);
    let lift = cross(spin_axis, v);
    let lift_len = length3(lift);
    let force = |i: usize| k * (-cd * speed * v[i] + cl * speed * speed * lift[i] / lift_len);
    [v[0], v[1], v[2], force(0), force(1) - GRAVITY, force(2)]
}

/// One step of classic fourth-order Runge–Kutta.
fn rk4_step(y: &BallState, h: f64, f: impl Fn(&BallState) -> BallState) -> BallState {
    let along = |k: &BallState, c: f64| std::array::from_fn(|i| y[i] + c * k[i]);
    let k1 = f(y);
    let k2 = f(&along(&k1, h / 2.0));
    let k3 = f(&along(&k2, h / 2.0));
    let k4 = f(&along(&k3, h));
    std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

fn fly(launch: &Launch) -> Flight {
    let (elevation, azimuth) = (
        launch.elevation_deg.to_radians(),
        launch.azimuth_deg.to_radians(),
    );
    let mut state = [
        0.0,
        LAUNCH_HEIGHT,
        0.0,
        launch.speed * elevation.cos() * azimuth.cos(),
        launch.speed * elevation.sin(),
        launch.speed * elevation.cos() * azimuth.sin(),
    ];
    // Backspin: the axis is horizontal, square to the launch direction, on the side that
    // makes ω̂ × v̂ point up; it stays fixed in space.
    let spin_axis = [-azimuth.sin(), 0.0, azimuth.cos()];
    let h = 1.0 / (TICK_HZ * SUBSTEPS as f64);
    let mut at_ticks = vec![state];
    let mut landing = None;
    while at_ticks.last().expect("the launch point")[1] >= 0.0 {
        for _ in 0..SUBSTEPS {
            let next = rk4_step(&state, h, |y| {
                ball_derivative(y, spin_axis, launch.spin_rpm)
            });
            if landing.is_none() && next[1] < 0.0 {
                // Linear interpolation on a 1/240 s step: the path leaves its chord by at
                // most |a|·h²/8, a few hundredths of a millimetre.
                let s = state[1] / (state[1] - next[1]);
                landing = Some([
                    state[0] + s * (next[0] - state[0]),
                    state[2] + s * (next[2] - state[2]),
                ]);
            }
            state = next;
        }
        at_ticks.push(state);
    }
    Flight {
        at_ticks,
        landing: landing.expect("the flight ends below the ground"),
    }
}

/// What the fielder's eye reads off the ball at one tick: tan ψ, the bearing α (from +x
/// toward +z), the horizontal distance d, and the rates of tan ψ and α.
struct Sight {
    tan_psi: f64,
    alpha: f64,
    distance: f64,
    tan_psi_rate: f64,
    alpha_rate: f64,
}

/// The ideal observer (no delay, no noise) sees the present as it is: the angles, and
/// their rates from the ball's velocity relative to the fielder's own.
fn look(ball: &BallState, fielder: [f64; 2], fielder_velocity: [f64; 2]) -> Sight {
    let (x, y, z) = (
        ball[0] - fielder[0],
        ball[1] - EYE_HEIGHT,
        ball[2] - fielder[1],
    );
    let (vx, vy, vz) = (
        ball[3] - fielder_velocity[0],
        ball[4],
        ball[5] - fielder_velocity[1],
    );
    let d = x.hypot(z);
    let d_rate = (x * vx + z * vz) / d;
    Sight {
        tan_psi: y / d,
        alpha: z.atan2(x),
        distance: d,
        tan_psi_rate: (vy * d - y * d_rate) / (d * d),
        alpha_rate: (x * vz - z * vx) / (d * d),
    }
}

/// A fielder's run: whether it caught the ball, and where it stood at each tick.
struct Run {
    caught: bool,
    path: Vec<[f64; 2]>,
}

/// A fielder starting at `start` and running by Chapman's law, with Tresilian's lateral
/// term at `lateral_gain` (0 for `chapman-1d`).
fn chapman_run(flight: &Flight, start: [f64; 2], lateral_gain: f64) -> Run {
    let (mut pos, mut vel) = (start, [0.0, 0.0]);
    let mut path = Vec::new();
    let mut held_rate: Option<f64> = None;
    for (tick, segment) in flight.at_ticks.windows(2).enumerate() {
        path.push(pos);
        let now = look(&segment[0], pos, vel);
        // The law acts after the reaction time.
        let reacted = tick as f64 / TICK_HZ >= REACTION_S;
        let command = if reacted {
            chapman_law(&now, &mut held_rate, lateral_gain)
        } else {
            [0.0, 0.0]
        };
        let (next_pos, next_vel) = move_body(pos, vel, command);
        if passes_within(&segment[0], &segment[1], pos, next_pos, REACH) {
            return Run { caught: true, path };
        }
        (pos, vel) = (next_pos, next_vel);
    }
    Run {
        caught: false,
        path,
    }
}

/// Chapman's law with Tresilian's lateral term at `lateral_gain`, once the ball is
/// clearly above the eye (the fielder stands until then, and runs on without a command in
/// the last ticks before a catch below it); the rate of tan ψ at its first step is the
/// one it holds.
fn chapman_law(now: &Sight, held_rate: &mut Option<f64>, lateral_gain: f64) -> [f64; 2] {
    if now.tan_psi < CLEARLY_ABOVE {
        return [0.0, 0.0];
    }
    let held = *held_rate.get_or_insert(now.tan_psi_rate);
    let toward = [now.alpha.cos(), now.alpha.sin()];
    let sideways = [-toward[1], toward[0]];
    let radial = -RADIAL_GAIN * now.distance / now.tan_psi * (now.tan_psi_rate - held);
    let lateral = lateral_gain * now.distance * now.alpha_rate;
    std::array::from_fn(|i| radial * toward[i] + lateral * sideways[i])
}

/// The body over one tick: the acceleration's length clipped (its direction kept), then
/// the speed's; constant acceleration over the tick moves it by the mean velocity.
fn move_body(pos: [f64; 2], vel: [f64; 2], command: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let dt = 1.0 / TICK_HZ;
    let accel = scale(command, (TOP_ACCEL / length2(command)).min(1.0));
    let pushed = [vel[0] + accel[0] * dt, vel[1] + accel[1] * dt];
    let next_vel = scale(pushed, (TOP_SPEED / length2(pushed)).min(1.0));
    let next_pos = [
        pos[0] + 0.5 * (vel[0] + next_vel[0]) * dt,
        pos[1] + 0.5 * (vel[1] + next_vel[1]) * dt,
    ];
    (next_pos, next_vel)
}

/// What the human fielder keeps of one look: when, tan ψ, α, the distance and its rate
/// if the ball is within the cue's range, and where it stood and how it moved.
struct Memory {
    t: f64,
    tan_psi: f64,
    alpha: f64,
    cue: Option<(f64, f64)>,
    pos: [f64; 2],
    vel: [f64; 2],
}

/// The least-squares parabola y = a + b·s + c·s² through `points` (s, y), solved from its
/// normal equations by Gaussian elimination: its value and slope at `at`.
fn parabola_at(points: &[(f64, f64)], at: f64) -> (f64, f64) {
    let mut m = [[0.0; 4]; 3];
    for &(s, y) in points {
        let powers = [1.0, s, s * s];
        for (row, p) in m.iter_mut().zip(powers) {
            for (k, q) in powers.iter().enumerate() {
                row[k] += p * q;
            }
            row[3] += p * y;
        }
    }
    for col in 0..3 {
        let pivot = (col..3)
            .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
            .unwrap();
        m.swap(col, pivot);
        let pivot_row = m[col];
        for (row, entries) in m.iter_mut().enumerate() {
            if row != col {
                let f = entries[col] / pivot_row[col];
                for (x, p) in entries.iter_mut().zip(pivot_row).skip(col) {
                    *x -= f * p;
                }
            }
        }
    }
    let [a, b, c] = std::array::from_fn(|i| m[i][3] / m[i][i]);
    (a + b * at + c * at * at, b + 2.0 * c * at)
}

/// A fielder with the human observer's senses less their errors, running by Chapman's
/// law with Tresilian's lateral term and finishing the catch (docs/catching.md, "What a
/// fielder sees" and "Observers").
fn human_chapman_run(flight: &Flight, start: [f64; 2]) -> Run {
    let dt = 1.0 / TICK_HZ;
    let delay = (HUMAN_DELAY_S * TICK_HZ).round() as usize;
    let window = 3.max((HUMAN_WINDOW_S * TICK_HZ).round() as usize + 1);
    let ahead = delay as f64 * dt;
    let catch_height = 0.5 * (CATCH_BAND.0 + CATCH_BAND.1) - EYE_HEIGHT;
    let (mut pos, mut vel) = (start, [0.0, 0.0]);
    let mut path = Vec::new();
    let mut memories: Vec<Memory> = Vec::new();
    let mut held_rate: Option<f64> = None;
    let mut finishing = false;
    for (tick, segment) in flight.at_ticks.windows(2).enumerate() {
        path.push(pos);
        let t = tick as f64 * dt;
        let ball = &segment[0];
        let seen = look(ball, pos, vel);
        // The closing speed along the line of sight, as the ball's true motion gives it.
        let (x, z) = (ball[0] - pos[0], ball[2] - pos[1]);
        let closing = (x * (ball[3] - vel[0]) + z * (ball[5] - vel[1])) / seen.distance;
        memories.push(Memory {
            t,
            tan_psi: seen.tan_psi,
            alpha: seen.alpha,
            cue: (seen.distance <= HUMAN_CUE_RANGE).then_some((seen.distance, closing)),
            pos,
            vel,
        });
        let mut command = [0.0, 0.0];
        if t >= REACTION_S && memories.len() >= delay + window {
            let newest = &memories[memories.len() - 1 - delay];
            let fitted = &memories[memories.len() - delay - window..memories.len() - delay];
            let points = |f: &dyn Fn(&Memory) -> f64| -> Vec<(f64, f64)> {
                fitted.iter().map(|m| (m.t - newest.t, f(m))).collect()
            };
            let (tan_psi, tan_psi_rate) = parabola_at(&points(&|m| m.tan_psi), ahead);
            // Bearings taken about the newest, so none jumps by a turn.
            let unwrapped = |m: &Memory| {
                let mut a = m.alpha - newest.alpha;
                while a > PI {
                    a -= TAU;
                }
                while a < -PI {
                    a += TAU;
                }
                newest.alpha + a
            };
            let (alpha, alpha_rate) = parabola_at(&points(&unwrapped), ahead);
            let (d, d_rate) = match newest.cue {
                Some((d, rate)) => (d + rate * ahead, rate),
                None => (HUMAN_CUE_RANGE, 0.0),
            };
            // Rebuilt relative to the eye, moved by the fielder's own extra movement.
            let (c, s) = (alpha.cos(), alpha.sin());
            let extra = [
                pos[0] - newest.pos[0] - newest.vel[0] * ahead,
                pos[1] - newest.pos[1] - newest.vel[1] * ahead,
            ];
            let sped = [vel[0] - newest.vel[0], vel[1] - newest.vel[1]];
            let r = [d * c - extra[0], d * tan_psi, d * s - extra[1]];
            let v = [
                d_rate * c - d * s * alpha_rate - sped[0],
                d_rate * tan_psi + d * tan_psi_rate,
                d_rate * s + d * c * alpha_rate - sped[1],
            ];
            let d = r[0].hypot(r[2]);
            let d_rate = (r[0] * v[0] + r[2] * v[2]) / d;
            let now = Sight {
                tan_psi: r[1] / d,
                alpha: r[2].atan2(r[0]),
                distance: d,
                tan_psi_rate: (v[1] * d - r[1] * d_rate) / (d * d),
                alpha_rate: (r[0] * v[2] - r[2] * v[0]) / (d * d),
            };
            command = chapman_law(&now, &mut held_rate, LATERAL_GAIN);
            // The finish: where the judged ball comes down through the catch height under
            // gravity alone, if the cue gives a distance and the ball is falling to it.
            let disc = v[1] * v[1] + 2.0 * GRAVITY * (r[1] - catch_height);
            if newest.cue.is_some() && v[1] < 0.0 && disc >= 0.0 {
                let fall = (v[1] + disc.sqrt()) / GRAVITY;
                finishing |= fall <= HUMAN_FINISH_S;
                if finishing {
                    let goal = [
                        pos[0] + r[0] + (v[0] + vel[0]) * fall,
                        pos[1] + r[2] + (v[2] + vel[1]) * fall,
                    ];
                    let to_go = [goal[0] - pos[0], goal[1] - pos[1]];
                    let distance = length2(to_go);
                    let on_time = distance / fall.max(dt);
                    let stopping = (2.0 * TOP_ACCEL * distance).sqrt();
                    let speed = TOP_SPEED.min(stopping.max(on_time)).min(distance / dt);
                    let wanted = if distance > 0.0 {
                        scale(to_go, speed / distance)
                    } else {
                        [0.0, 0.0]
                    };
                    command = [(wanted[0] - vel[0]) / dt, (wanted[1] - vel[1]) / dt];
                }
            }
        }
        let (next_pos, next_vel) = move_body(pos, vel, command);
        let reach = HUMAN_REACH + if finishing { HUMAN_LUNGE } else { 0.0 };
        if passes_within(&segment[0], &segment[1], pos, next_pos, reach) {
            return Run { caught: true, path };
        }
        (pos, vel) = (next_pos, next_vel);
    }
    Run {
        caught: false,
        path,
    }
}

/// The catch zone on the segment between two ticks (ball and fielder each moving in a
/// straight line along it): a descending ball whose horizontal distance from the fielder
/// is within `reach` at some instant while its height is in the catch band.
fn passes_within(
    ball0: &BallState,
    ball1: &BallState,
    f0: [f64; 2],
    f1: [f64; 2],
    reach: f64,
) -> bool {
    let drop = ball0[1] - ball1[1];
    if drop <= 0.0 {
        return false;
    }
    // The share s of the segment at which the ball enters and leaves the band.
    let enter = (ball0[1] - CATCH_BAND.1) / drop;
    let leave = (ball0[1] - CATCH_BAND.0) / drop;
    if enter > 1.0 || leave < 0.0 {
        return false;
    }
    let (enter, leave) = (enter.max(0.0), leave.min(1.0));
    // The horizontal offset ball − fielder is p + s·q; take its shortest in [enter, leave].
    let p = [ball0[0] - f0[0], ball0[2] - f0[1]];
    let q = [
        ball1[0] - ball0[0] - (f1[0] - f0[0]),
        ball1[2] - ball0[2] - (f1[1] - f0[1]),
    ];
    let qq = q[0] * q[0] + q[1] * q[1];
    let closest = if qq > 0.0 {
        (-(p[0] * q[0] + p[1] * q[1]) / qq).clamp(enter, leave)
    } else {
        enter
    };
    length2([p[0] + closest * q[0], p[1] + closest * q[1]]) <= reach
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn length3(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn length2(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

fn scale(v: [f64; 2], k: f64) -> [f64; 2] {
    [v[0] * k, v[1] * k]
}

/// The distance between two points on the ground.
fn apart(a: [f64; 2], b: [f64; 2]) -> f64 {
    length2([a[0] - b[0], a[1] - b[1]])
}

/// The sweeps' launch distribution (docs/catching.md, "Experiments"), drawn here: the
/// fielder starts 10–40 m from where this file's own flight lands, in any direction.
fn launches(n: usize, seed: u64) -> Vec<(Launch, Flight)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let mut launch = Launch {
                speed: rng.gen_range(25.0..45.0),
                elevation_deg: rng.gen_range(25.0..65.0),
                azimuth_deg: rng.gen_range(0.0..90.0),
                spin_rpm: rng.gen_range(1000.0..3000.0),
                fielder: [0.0, 0.0],
            };
            let flight = fly(&launch);
            let (r, heading) = (rng.gen_range(10.0..40.0), rng.gen_range(0.0..TAU));
            launch.fielder = [
                flight.landing[0] + r * heading.cos(),
                flight.landing[1] + r * heading.sin(),
            ];
            (launch, flight)
        })
        .collect()
}

/// The real binary on one launch, with the ideal observer (no delay, no noise): its
/// decision, the fielder at each tick of its trace, and where it says the ball lands.
fn binary_run(launch: &Launch, strategy: &str, flags: &str) -> (Run, [f64; 2]) {
    let doc = common::json(&format!(
        "catch --strategy {strategy} {flags} --speed {} --elevation {} --azimuth {} --spin {} \
         --fielder {},{} --json",
        launch.speed,
        launch.elevation_deg,
        launch.azimuth_deg,
        launch.spin_rpm,
        launch.fielder[0],
        launch.fielder[1]
    ));
    let pair = |v: &serde_json::Value| -> [f64; 2] {
        std::array::from_fn(|i| v[i].as_f64().expect("a pair of numbers"))
    };
    let path = doc["trace"]
        .as_array()
        .expect("a trace")
        .iter()
        .map(|entry| pair(&entry["fielder"]))
        .collect();
    let outcome = &doc["outcome"];
    let run = Run {
        caught: outcome["caught"].as_bool().expect("caught is a boolean"),
        path,
    };
    (run, pair(&outcome["ball_landing"]))
}

/// One launch as both sides see it.
struct Comparison {
    /// For chapman, chapman-1d, then chapman with the human senses less their errors:
    /// the oracle's run and the binary's.
    runs: [(Run, Run); 3],
    landing_error: f64,
}

fn compare(launch: &Launch, flight: &Flight) -> Comparison {
    let (chapman, landing) = binary_run(launch, "chapman", "");
    let (chapman_1d, _) = binary_run(launch, "chapman-1d", "");
    let (human, _) = binary_run(launch, "chapman", HUMAN_FLAGS);
    Comparison {
        runs: [
            (chapman_run(flight, launch.fielder, LATERAL_GAIN), chapman),
            (chapman_run(flight, launch.fielder, 0.0), chapman_1d),
            (human_chapman_run(flight, launch.fielder), human),
        ],
        landing_error: apart(landing, flight.landing),
    }
}

/// The largest distance between two runs' fielders at the same tick.
fn path_gap(a: &Run, b: &Run) -> f64 {
    a.path
        .iter()
        .zip(&b.path)
        .map(|(p, q)| apart(*p, *q))
        .fold(0.0, f64::max)
}

#[test]
fn an_independent_chapman_fielder_catches_the_balls_the_binary_catches() {
    let trials = launches(300, 25);
    // The binary runs 600 times; four threads keep the cores busy while processes start.
    let compared: Vec<Comparison> = std::thread::scope(|scope| {
        let workers: Vec<_> = trials
            .chunks(trials.len().div_ceil(4))
            .map(|chunk| {
                scope.spawn(move || {
                    chunk
                        .iter()
                        .map(|(launch, flight)| compare(launch, flight))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a worker finished"))
            .collect()
    });
    let share = |pick: &dyn Fn(&Comparison) -> bool| {
        compared.iter().filter(|c| pick(c)).count() as f64 / compared.len() as f64
    };
    // Per strategy, the catch rates of the oracle and of the binary.
    let mut rates = [[0.0; 2]; 3];
    for (k, name) in ["chapman", "chapman-1d", "chapman (human senses, no errors)"]
        .into_iter()
        .enumerate()
    {
        rates[k] = [
            share(&|c| c.runs[k].0.caught),
            share(&|c| c.runs[k].1.caught),
        ];
        let agreement = share(&|c| c.runs[k].0.caught == c.runs[k].1.caught);
        let mut gaps: Vec<f64> = compared
            .iter()
            .map(|c| path_gap(&c.runs[k].0, &c.runs[k].1))
            .collect();
        gaps.sort_by(f64::total_cmp);
        let (gap_90th, gap_worst) = (gaps[gaps.len() * 9 / 10], gaps[gaps.len() - 1]);
        eprintln!(
            "{name}: caught {:.1}% (oracle) and {:.1}% (binary) of {} launches, the same \
             decision on {:.1}%; largest gap between the paths: median {:.4} m, 90th \
             percentile {:.4} m, worst {:.4} m",
            100.0 * rates[k][0],
            100.0 * rates[k][1],
            compared.len(),
            100.0 * agreement,
            gaps[gaps.len() / 2],
            gap_90th,
            gap_worst,
        );
        // (a) The bound: the two catch rates within 3 percentage points.
        assert!(
            (rates[k][0] - rates[k][1]).abs() <= 0.03,
            "{name}: the catch rates differ: {:?}",
            rates[k]
        );
        // (b) The same balls, not only as many. The paths agree to millimetres (below),
        // so a decision can differ only for a ball that passes within about that of the
        // edge of the reach or of the catch band's ends. There were none in 300 when
        // this was written; 99 % leaves room for three such balls, and fails a side that
        // catches other balls at a similar rate: an oracle without the lunge catches
        // 72.7 % against 75.0 %, within the 3 points of (a), but decides 7 balls
        // differently (97.7 %).
        assert!(
            agreement >= 0.99,
            "{name}: the same decision on only {:.1}% of launches",
            100.0 * agreement
        );
        // The same runs: the fielders agree tick by tick. The oracle's ideal eye reads
        // the true rates; the library's fits its last three looks with quadratics in
        // time, exact to the square of the tick: 2 mm apart (median), 3 mm (90th
        // percentile), 1.1 cm at worst. With the human senses both fit their windows,
        // but the oracle judges the closing speed from the ball's true velocity where
        // the library differences the distance over a tick; in the finishing phase that
        // parts them by up to 11 cm. These errors in the oracle fail here (measured
        // on the ideal observer): K or K_lat 10 % off,
        // 8.4 m/s, 4.4 m/s², a 0.35 s reaction, "clearly above" at tan ψ = 0.06 (90th
        // percentile 19–47 cm), the eye at 1.6 m (14 cm), the lateral term acting before
        // the first step (worst 1.05 m), no d/tan ψ factor (3.2 m, though the rates
        // agree within 3 points and the decisions on 98 %: decisions alone would not
        // catch it).
        assert!(
            gap_90th <= 0.12 && gap_worst <= 0.3,
            "{name}: the paths differ by {gap_90th:.3} m at the 90th percentile, \
             {gap_worst:.3} m at worst"
        );
    }
    // (c) The physics on its own: the same landing points. Both integrators are exact to
    // well under a millimetre; the measured 2.5 mm is the library's rounding of 9.125 in
    // to 0.23178 m (with its figure the two agree to 2·10⁻⁵ m). An air density 1 % off
    // moves a landing 0.56 m, g = 9.80665 instead of 9.81 moves it 3 cm.
    let worst_landing = compared.iter().map(|c| c.landing_error).fold(0.0, f64::max);
    eprintln!("landing points: at most {worst_landing:.4} m apart");
    assert!(
        worst_landing <= 0.01,
        "landing points {worst_landing} m apart"
    );
    // (d) The comparison tells a right law from a wrong one: without the lateral term
    // each side catches a small fraction of what it catches with it (and above, the two
    // sides agree on which).
    let [chapman, chapman_1d, _] = rates;
    for side in 0..2 {
        assert!(
            chapman_1d[side] < chapman[side] / 4.0,
            "chapman-1d is not far below chapman: {chapman_1d:?} vs {chapman:?}"
        );
    }
}
