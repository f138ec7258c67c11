//! Basketball benchmarks on the CMU motion capture embedded in the binary: one
//! opponent-modelling decision, and a 10-minute 2-v-1 match at 60 Hz once the maps are
//! built.
//!
//! Run with `cargo bench --bench basketball`; results are written up in BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, Criterion};
use fieldhouse::basketball::{
    Brain, Capabilities, Court, DecisionParams, Game, GameParams, Keep, Motion, Opponent,
    ShotModel, Situation,
};
use fieldhouse::costmap::cache::Reuse;
use fieldhouse::costmap::AgentPose;
use fieldhouse::motion::{Mirroring, MotionLibrary, FPS};
use glam::DVec2;
use std::hint::black_box;
use std::sync::Arc;

fn capabilities() -> Arc<Capabilities> {
    let library = MotionLibrary::embedded(FPS, Mirroring::On);
    Arc::new(
        Capabilities::build(&library, Reuse::Shipped, &mut |_| {}).expect("the behaviours build"),
    )
}

/// Target: every graph and every map of every behaviour and start state, as a first
/// start builds them with no cache, in under 10 s.
fn capabilities_uncached(c: &mut Criterion) {
    let library = MotionLibrary::embedded(FPS, Mirroring::On);
    let mut group = c.benchmark_group("basketball/capabilities");
    group.sample_size(10);
    group.bench_function("all_graphs_and_maps_uncached", |b| {
        b.iter(|| black_box(Capabilities::build(&library, Reuse::Nothing, &mut |_| {}).unwrap()))
    });
    group.finish();
}

/// Target: a decision over a 20 m × 20 m map of 0.5 m cells in under 50 µs.
fn decision(c: &mut Criterion) {
    let caps = capabilities();
    let court = Court::default();
    let shot = ShotModel::default();
    let params = DecisionParams::default();
    let defender = AgentPose {
        position: DVec2::new(4.0, 0.0),
        heading: 0.0,
    };
    let defenders = [Opponent::Map(caps.run.reach(&defender, Motion::Still))];
    let shooter = AgentPose {
        position: DVec2::new(9.0, 2.0),
        heading: std::f64::consts::PI,
    };
    let situation = Situation {
        court: &court,
        shot: &shot,
        params: &params,
        shooter: caps.dribble.reach(&shooter, Motion::Still),
        defenders: &defenders,
        shot_clock_s: 24.0,
    };
    let mut candidates = Vec::new();
    for (name, keep) in [("all", Keep::All), ("qualifying", Keep::Qualifying)] {
        c.bench_function(&format!("basketball/decision/{name}"), |b| {
            b.iter(|| black_box(situation.decide_into(&mut candidates, keep)))
        });
    }
}

/// Target: a 10-minute 2-v-1 match at 60 Hz (36,000 ticks) in under 0.1 s.
fn match_10_minutes(c: &mut Criterion) {
    let caps = capabilities();
    let mut group = c.benchmark_group("basketball/match_10_min_60hz");
    group.sample_size(10);
    for offense in [Brain::Simple, Brain::Costmap] {
        group.bench_function(offense.name(), |b| {
            b.iter(|| {
                let mut game = Game::new(
                    caps.clone(),
                    GameParams {
                        offense,
                        ..GameParams::default()
                    },
                );
                let mut events = Vec::new();
                for _ in 0..36_000 {
                    events.clear();
                    game.step(&mut events);
                }
                black_box(game.score())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, capabilities_uncached, decision, match_10_minutes);
criterion_main!(benches);
