//! The catching claims checked against analytic oracles: closed-form optics of a
//! parabola, closed-form reachability, and the human limits themselves.

use super::strategy::Forecast;
use super::*;
use crate::perception::Sighting;
use crate::physics::{AirModel, BallSpec, Flight, Launch, GRAVITY, NATHAN_AIR_DENSITY};
use glam::{DVec2, DVec3};

const DT: f64 = 1.0 / 60.0;

fn vacuum_flight_from_eye(speed: f64, elevation_deg: f64, eye: f64) -> Flight {
    let launch = Launch {
        speed_m_s: speed,
        elevation_deg,
        azimuth_deg: 0.0,
        height_m: eye,
        spin_rpm: 0.0,
        spin_tilt_deg: 0.0,
    };
    let air = launch.air(AirModel::Vacuum, NATHAN_AIR_DENSITY, &BallSpec::BASEBALL);
    Flight::simulate(launch.initial_state(), &air, DT, 30.0)
}

fn sweep(limits: Limits) -> Sweep {
    Sweep {
        ball: BallSpec::BASEBALL,
        air: AirModel::Nathan,
        air_density: NATHAN_AIR_DENSITY,
        dt: DT,
        trial: TrialConfig {
            fielder: FielderConfig {
                limits,
                ..FielderConfig::default()
            },
            ..TrialConfig::default()
        },
        observer: Observer::IDEAL,
    }
}

/// Chapman (1968): a fielder standing where a vacuum ball launched at eye height comes
/// back to eye height sees tan ψ = g·t / (2·V·cos θ), a straight line in time.
#[test]
fn standing_at_the_landing_point_tan_psi_rises_at_chapmans_rate() {
    let (v, theta) = (30.0, 45f64.to_radians());
    let g = -GRAVITY.y;
    let slope = g / (2.0 * v * theta.cos());
    assert!((slope - 0.2312).abs() < 1e-4, "worked value: {slope}");
    let flight = vacuum_flight_from_eye(v, 45.0, 1.7);
    let landing = DVec2::new(v * v * (2.0 * theta).sin() / g, 0.0);
    let config = TrialConfig {
        record_trace: true,
        ..TrialConfig::default()
    };
    // `chapman` sees zero optical acceleration here, so it must stand still.
    let r = Trial {
        flight: &flight,
        config: &config,
    }
    .run(StrategyKind::Chapman, landing);
    assert!(r.outcome.caught, "{:?}", r.outcome);
    assert!(
        r.path_length_m < 1e-6,
        "a fielder already in place ran {} m",
        r.path_length_m
    );
    for e in &r.trace {
        assert!(
            (e.tan_psi - slope * e.t).abs() < 1e-9 * (1.0 + e.tan_psi),
            "t = {}: {} vs {}",
            e.t,
            e.tan_psi,
            slope * e.t
        );
    }
}

/// Any constant-velocity run that arrives exactly when the ball does sees tan ψ rise
/// linearly, at g / (2·closing speed) for a ball launched at eye height.
#[test]
fn a_constant_velocity_run_that_arrives_in_time_sees_tan_psi_rise_linearly() {
    let eye = 1.7;
    let flight = vacuum_flight_from_eye(32.0, 50.0, eye);
    let g = -GRAVITY.y;
    let t_end = 2.0 * 32.0 * 50f64.to_radians().sin() / g;
    let ball_at =
        |t: f64| flight.samples[0].pos + flight.samples[0].vel * t + 0.5 * GRAVITY * t * t;
    let meet = ball_at(t_end);
    let meet = DVec2::new(meet.x, meet.z);
    for start in [
        DVec2::new(60.0, 25.0),
        DVec2::new(120.0, -30.0),
        DVec2::new(80.0, 0.0),
    ] {
        let f_vel = (meet - start) / t_end;
        let b_vel = DVec2::new(flight.samples[0].vel.x, flight.samples[0].vel.z);
        let closing = (f_vel - b_vel).length();
        for s in flight
            .samples
            .iter()
            .filter(|s| s.t > 0.1 && s.t < t_end - 0.1)
        {
            let seen = Sighting::of(s.t, s.pos, start + f_vel * s.t, eye);
            let expected = g * s.t / (2.0 * closing);
            assert!(
                (seen.tan_psi - expected).abs() < 1e-9,
                "start {start}: {} vs {expected}",
                seen.tan_psi
            );
        }
    }
}

/// `chapman` asks for whatever it likes; the body never delivers more than the limits.
#[test]
fn chapman_never_exceeds_the_human_limits() {
    let sweep = sweep(Limits::HUMAN);
    let cases = sweep.cases(&LaunchDistribution::default(), 40, 11);
    for (i, case) in cases.iter().enumerate() {
        let r = sweep.trial(i, case, StrategyKind::Chapman, true);
        assert!(r.peak_accel <= 4.5 + 1e-9 && r.peak_speed <= 8.5 + 1e-9);
        for e in &r.trace {
            let a = DVec2::from_array(e.accel).length();
            assert!(a <= 4.5 + 1e-9, "case {i} at {} s: |a| = {a}", e.t);
            if e.t < 0.3 {
                assert_eq!(a, 0.0, "moved before the reaction time");
            }
        }
    }
}

/// `predictive` defines catchability, so check it against closed-form reachability: a
/// ball whose band crossing a straight sprint reaches with time to spare is caught; a
/// ball no point of whose descent through the band can be reached in time is not.
#[test]
fn predictive_catches_exactly_what_closed_form_reachability_allows() {
    let l = Limits::HUMAN;
    let sweep = sweep(l);
    let zone = CatchZone::default();
    let cases = sweep.cases(&LaunchDistribution::default(), 300, 5);
    let (mut surely, mut never) = (0, 0);
    for (i, case) in cases.iter().enumerate() {
        let caught = sweep
            .trial(i, case, StrategyKind::Predictive, false)
            .outcome
            .caught;
        let Forecast { point, t } = Trial {
            flight: &case.flight,
            config: &sweep.trial,
        }
        .forecast();
        if l.sprint_time((point - case.start).length()) < t - 0.15 {
            surely += 1;
            assert!(caught, "case {i}: reachable with time to spare but missed");
        }
        // The best any runner could do: reach within `reach` of some point of the
        // descending band before the ball gets there.
        let reachable_somewhere = case
            .flight
            .samples
            .iter()
            .filter(|s| {
                s.vel.y < 0.0
                    && s.pos.y <= zone.max_height_m + 0.5
                    && s.pos.y >= zone.min_height_m - 0.5
            })
            .any(|s| {
                let d = (DVec2::new(s.pos.x, s.pos.z) - case.start).length() - zone.reach_m;
                l.sprint_time(d) <= s.t + 0.05
            });
        if !reachable_somewhere {
            never += 1;
            assert!(!caught, "case {i}: caught a ball no sprint could reach");
        }
    }
    assert!(
        surely > 100 && never > 30,
        "oracle too weak: {surely} surely, {never} never"
    );
}

/// The targets on catchable balls with human limits (docs/catching.md): chapman ≥ 95 %,
/// lot-optical ≥ 90 %; and the theories the papers call unrealistic fail with limits.
#[test]
fn optical_strategies_catch_what_is_catchable() {
    let dist = LaunchDistribution::default();
    let sweep = sweep(Limits::HUMAN);
    let cases = sweep.cases(&dist, 400, 21);
    let report = sweep.run(&cases, &StrategyKind::ALL, &dist, 21);
    let rate = |k: StrategyKind| {
        report
            .strategies
            .iter()
            .find(|s| s.strategy == k)
            .unwrap()
            .catchable_rate
    };
    assert!(report.strategies[0].catchable > 200);
    assert_eq!(rate(StrategyKind::Predictive), 1.0);
    assert!(
        rate(StrategyKind::Chapman) >= 0.95,
        "chapman {}",
        rate(StrategyKind::Chapman)
    );
    assert!(
        rate(StrategyKind::LotOptical) >= 0.90,
        "lot-optical {}",
        rate(StrategyKind::LotOptical)
    );
    assert!(
        rate(StrategyKind::Chapman1d) < 0.2,
        "chapman-1d {}",
        rate(StrategyKind::Chapman1d)
    );
    assert!(
        rate(StrategyKind::Lot) < 0.2,
        "lot {}",
        rate(StrategyKind::Lot)
    );
}

/// Without limits Gillies & Dodgson's `lot` does catch, at superhuman speeds: the
/// reason it fails with limits.
#[test]
fn lot_catches_without_limits_but_needs_superhuman_speed() {
    let dist = LaunchDistribution::default();
    let sweep = sweep(Limits::NONE);
    let cases = sweep.cases(&dist, 60, 8);
    let report = sweep.run(&cases, &[StrategyKind::Lot], &dist, 8);
    let lot = &report.strategies[0];
    assert!(lot.catch_rate > 0.9, "{}", lot.catch_rate);
    assert!(lot.mean_peak_speed > 12.0, "{}", lot.mean_peak_speed);
}

#[test]
fn sweeps_are_deterministic_and_independent_of_threads() {
    let dist = LaunchDistribution::default();
    let sweep = sweep(Limits::HUMAN);
    let run = || {
        let cases = sweep.cases(&dist, 30, 3);
        serde_json::to_string(&sweep.run(&cases, &StrategyKind::ALL, &dist, 3)).unwrap()
    };
    let parallel = run();
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(run);
    assert_eq!(parallel, single);
}

#[test]
fn the_ball_is_never_read_ahead() {
    // Two flights identical up to 2 s and different after: every strategy but
    // `predictive` must act identically up to then.
    let a = vacuum_flight_from_eye(35.0, 50.0, 1.7);
    let mut b = a.clone();
    for s in b.samples.iter_mut().filter(|s| s.t > 2.0) {
        s.pos += DVec3::new(5.0, 0.0, 5.0);
    }
    let config = TrialConfig {
        record_trace: true,
        ..TrialConfig::default()
    };
    for k in [
        StrategyKind::Chapman,
        StrategyKind::Chapman1d,
        StrategyKind::Lot,
        StrategyKind::LotOptical,
    ] {
        let ra = Trial {
            flight: &a,
            config: &config,
        }
        .run(k, DVec2::new(90.0, 20.0));
        let rb = Trial {
            flight: &b,
            config: &config,
        }
        .run(k, DVec2::new(90.0, 20.0));
        for (ea, eb) in ra.trace.iter().zip(&rb.trace).filter(|(e, _)| e.t <= 2.0) {
            assert_eq!(ea.accel, eb.accel, "{k} reacted to the future at {}", ea.t);
        }
    }
}
