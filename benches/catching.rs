//! Catching benchmarks: the 10,000-catch sweep target and its parts.
//!
//! Run with `cargo bench --bench catching`; results are written up in BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use fieldhouse::fielding::{LaunchDistribution, Observer, StrategyKind, Sweep, TrialConfig};
use fieldhouse::physics::{AirModel, BallSpec, Launch, NATHAN_AIR_DENSITY};
use std::hint::black_box;

fn sweep() -> Sweep {
    Sweep {
        ball: BallSpec::BASEBALL,
        air: AirModel::Nathan,
        air_density: NATHAN_AIR_DENSITY,
        dt: 1.0 / 60.0,
        trial: TrialConfig::default(),
        observer: Observer::IDEAL,
    }
}

/// The target: 10,000 catches at 60 Hz in Nathan air, launches drawn and flown included.
/// Measured two ways: 2,000 launches × all five strategies, and 10,000 launches × one.
/// Each launch also runs `predictive` once more to decide catchability, so the first is
/// 12,000 trials and the second 20,000: both more than 10,000 catches of work.
fn sweeps(c: &mut Criterion) {
    let dist = LaunchDistribution::default();
    let s = sweep();
    let mut group = c.benchmark_group("catch_sweep");
    group.sample_size(10);
    for (launches, strategies) in [
        (2_000usize, &StrategyKind::ALL[..]),
        (10_000, &[StrategyKind::Chapman][..]),
    ] {
        group.throughput(Throughput::Elements((launches * strategies.len()) as u64));
        let name = format!("{launches}x{}", strategies.len());
        group.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter(|| {
                let cases = s.cases(&dist, launches, 1);
                black_box(s.run(&cases, strategies, &dist, 1))
            })
        });
    }
    group.finish();
}

fn single(c: &mut Criterion) {
    let s = sweep();
    let cases = s.cases(&LaunchDistribution::default(), 1, 3);
    let launch = Launch {
        speed_m_s: 40.0,
        elevation_deg: 40.0,
        azimuth_deg: 30.0,
        height_m: 1.0,
        spin_rpm: 2000.0,
        spin_tilt_deg: 0.0,
    };
    c.bench_function("flight_nathan_60hz", |b| {
        b.iter(|| black_box(s.fly(black_box(&launch))))
    });
    for k in StrategyKind::ALL {
        c.bench_function(&format!("trial_{k}"), |b| {
            b.iter(|| black_box(s.trial(0, &cases[0], k, false)))
        });
    }
}

criterion_group!(benches, sweeps, single);
criterion_main!(benches);
