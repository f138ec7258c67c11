//! Motion-graph and cost-map benchmarks on the CMU motion capture embedded in the binary.
//!
//! Run with `cargo bench --bench motion`; results are written up in BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fieldhouse::costmap::{BuildParams, CostMap, Method};
use fieldhouse::motion::{Clip, Mirroring, MotionGraph, MotionLibrary, AUTO_WINDOWS, FPS};
use std::hint::black_box;

fn library() -> MotionLibrary {
    MotionLibrary::embedded(FPS, Mirroring::On)
}

fn graph(library: &MotionLibrary, behaviour: &str) -> MotionGraph {
    let owned = library.ground_clips(behaviour);
    let clips: Vec<&Clip> = owned.iter().collect();
    MotionGraph::build_auto(behaviour, &clips, &AUTO_WINDOWS).unwrap()
}

/// Target: the motion graph over all frames of the motion capture, at 30 fps, in under
/// 10 s; and unpacking and parsing the embedded capture (`load_bvh_all`), which every
/// command does at start.
fn motion_graphs(c: &mut Criterion) {
    let library = library();
    let mut group = c.benchmark_group("motion_graph");
    group.sample_size(10);
    group.bench_function("all_behaviours_auto_threshold", |b| {
        b.iter(|| {
            for behaviour in ["defense", "dribble", "run"] {
                black_box(graph(&library, behaviour));
            }
        })
    });
    group.bench_function("load_bvh_all", |b| {
        b.iter(|| black_box(MotionLibrary::embedded(FPS, Mirroring::On)))
    });
    group.finish();
}

/// Target: `search` faster than 7,000 `mc` walks; mc walks per second.
fn cost_maps(c: &mut Criterion) {
    let library = library();
    let run = graph(&library, "run");
    let mut group = c.benchmark_group("costmap_run_20m");
    group.sample_size(10);
    for walks in [7_000u64, 200_000] {
        let params = BuildParams {
            method: Method::Mc,
            iterations: walks,
            ..BuildParams::default()
        };
        group.throughput(Throughput::Elements(walks));
        group.bench_function(format!("mc_{walks}"), |b| {
            b.iter(|| black_box(CostMap::build(&run, &params, &mut |_| {})))
        });
    }
    group.throughput(Throughput::Elements(1));
    for method in [Method::Search, Method::Grassfire] {
        let params = BuildParams {
            method,
            ..BuildParams::default()
        };
        group.bench_function(method.name(), |b| {
            b.iter(|| black_box(CostMap::build(&run, &params, &mut |_| {})))
        });
    }
    group.finish();
}

criterion_group!(benches, motion_graphs, cost_maps);
criterion_main!(benches);
