//! `fieldhouse costmap`: how many frames a human needs to reach each square around it.

use super::args::positive;
use super::heatmap;
use super::motion::GraphArgs;
use anyhow::Context;
use clap::Args;
use fieldhouse::costmap::{
    cache, root_speed, BuildParams, CostMap, Grid, Method, Obstacle, Start, WATCHED_POINTS,
};
use fieldhouse::motion::MotionGraph;
use fieldhouse::words::{figure, plural};
use glam::DVec2;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug)]
#[command(
    about = "Build a behaviour's cost map: frames to reach each cell from a start state",
    allow_negative_numbers = true,
    args_override_self = true,
    after_help = "The agent stands at (0, 0) facing +x; y is up, so +z is on its right.\n\
        Example: fieldhouse costmap --behaviour run --method search --png run.png"
)]
pub(super) struct CostmapArgs {
    /// mc (the paper's Monte Carlo), search (systematic minimum time) or grassfire
    /// (distance at top speed).
    #[arg(long, default_value = "search", value_parser = super::args::parse_str::<Method>)]
    method: Method,
    /// Monte Carlo walks.
    #[arg(long, default_value_t = BuildParams::default().iterations, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    iterations: u64,
    /// Longest walk (mc) or search horizon, in frames at 30 fps.
    #[arg(long, value_name = "FRAMES", default_value_t = BuildParams::default().depth, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    depth: u32,
    /// Side of the square map, metres.
    #[arg(long, value_name = "M", default_value_t = 20.0, value_parser = positive)]
    size: f64,
    /// Side of a cell, metres.
    #[arg(long, value_name = "M", default_value_t = 0.5, value_parser = positive)]
    cell: f64,
    /// A rectangle no path may enter, corners X0,Z0,X1,Z1 in metres (repeatable).
    #[arg(long, value_name = "X0,Z0,X1,Z1", value_parser = rectangle, allow_hyphen_values = true)]
    obstacle: Vec<Obstacle>,
    /// Where the body starts in the motion graph: default (running forward at about half
    /// the behaviour's top speed), standing (the slowest state the data offers), moving
    /// (the most common running state), a node id of the pruned graph (see motion-graph
    /// --json) or CLIP:FRAME.
    #[arg(
        long,
        visible_alias = "start-frame",
        value_name = "S",
        default_value = "default"
    )]
    start: String,
    /// Disable motion-graph edges faster than this, m/s.
    #[arg(long, value_name = "M_PER_S", value_parser = positive)]
    max_speed: Option<f64>,
    /// Seed of the Monte Carlo walks.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    cache: CacheArgs,
    /// Draw the map as a PNG heat map (dark = cheap).
    #[arg(long, value_name = "FILE")]
    png: Option<PathBuf>,
    /// Print one JSON document.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    graph: GraphArgs,
}

/// Where cost maps are cached.
#[derive(Args, Debug, Clone)]
pub(super) struct CacheArgs {
    /// Where built maps are cached (default: $XDG_CACHE_HOME/fieldhouse or ~/.cache/fieldhouse).
    #[arg(long, value_name = "DIR", env = "FIELDHOUSE_CACHE_DIR")]
    cache_dir: Option<PathBuf>,
    /// Build from the motion even if fieldhouse ships the graphs and maps or the cache
    /// holds them (and store nothing).
    #[arg(long)]
    no_cache: bool,
}

/// The default cache directory: `$XDG_CACHE_HOME/fieldhouse`, else `~/.cache/fieldhouse`.
/// Read here, at the edge: the core is told its directories.
fn default_cache_dir() -> Option<PathBuf> {
    std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .map(|d| d.join("fieldhouse"))
}

impl CacheArgs {
    /// The cache directory to use, if any.
    pub(super) fn dir(&self) -> Option<CacheDir> {
        (!self.no_cache)
            .then(|| self.cache_dir.clone().or_else(default_cache_dir))
            .flatten()
            .map(CacheDir)
    }

    /// Where graphs and maps may be found before they are built, with `dir` (this
    /// [`CacheArgs::dir`]) as the cache.
    pub(super) fn reuse<'a>(&self, dir: Option<&'a CacheDir>) -> cache::Reuse<'a> {
        match (self.no_cache, dir) {
            (true, _) => cache::Reuse::Nothing,
            (false, Some(dir)) => cache::Reuse::ShippedOrStore(dir),
            (false, None) => cache::Reuse::Shipped,
        }
    }
}

/// The cost-map cache's directory: a file per graph and its maps, named by its key.
pub(super) struct CacheDir(pub PathBuf);

impl cache::Store for CacheDir {
    fn load(&self, name: &str) -> std::io::Result<Option<Vec<u8>>> {
        match std::fs::read(self.0.join(name)) {
            Ok(bytes) => Ok(Some(bytes)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// Written atomically (a temporary file, synced, renamed over the name), so a reader
    /// never sees half a file and two writers leave one whole one.
    fn keep(&self, name: &str, bytes: &[u8]) -> std::io::Result<()> {
        std::fs::create_dir_all(&self.0)?;
        let mut file = tempfile::NamedTempFile::new_in(&self.0)?;
        file.write_all(bytes)?;
        file.as_file().sync_all()?;
        file.persist(self.0.join(name)).map_err(|e| e.error)?;
        Ok(())
    }
}

fn rectangle(s: &str) -> Result<Obstacle, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("\"{s}\" is not a rectangle; write X0,Z0,X1,Z1 in metres"))?;
    match v.as_slice() {
        [x0, z0, x1, z1] if x0 != x1 && z0 != z1 => {
            Ok(Obstacle::new(DVec2::new(*x0, *z0), DVec2::new(*x1, *z1)))
        }
        [_, _, _, _] => Err(format!("rectangle \"{s}\" has no area")),
        _ => Err(format!(
            "\"{s}\" is not a rectangle; write X0,Z0,X1,Z1 in metres"
        )),
    }
}

/// The graph node a `--start` names.
fn start_node(graph: &MotionGraph, given: &str) -> anyhow::Result<u32> {
    if let Ok(start) = given.parse::<Start>() {
        return start.node(graph).with_context(|| {
            format!(
                "start {given}: the graph has nodes 0 to {}",
                graph.node_count() - 1
            )
        });
    }
    let (clip, frame) = given
        .split_once(':')
        .and_then(|(c, f)| Some((c, f.parse::<usize>().ok()?)))
        .with_context(|| {
            format!("start \"{given}\": write default, standing, moving, a node id or CLIP:FRAME")
        })?;
    let c = graph
        .clip_names
        .iter()
        .position(|n| n == clip)
        .with_context(|| {
            format!(
                "start \"{given}\": no clip {clip}; clips: {}",
                graph.clip_names.join(", ")
            )
        })?;
    graph
        .nodes
        .iter()
        .position(|n| n.clip == c && n.frame == frame)
        .map(|i| i as u32)
        .with_context(|| format!("start \"{given}\" was pruned from the graph (not in its largest strongly connected component)"))
}

pub(super) fn run(args: CostmapArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let (library, graph) = args.graph.build()?;
    let start = start_node(&graph, &args.start)?;
    let params = BuildParams {
        method: args.method,
        grid: Grid::new(args.size, args.cell),
        iterations: args.iterations,
        depth: args.depth,
        seed: args.seed,
        max_speed: args.max_speed,
        start_node: Some(start),
        obstacles: args.obstacle.clone(),
        ..BuildParams::default()
    };
    anyhow::ensure!(
        params.grid.cells() <= 4_000_000,
        "a {} m map of {} m cells has too many cells",
        args.size,
        args.cell
    );
    let cache_dir = args.cache.dir();
    let started = Instant::now();
    let bar = (args.method == Method::Mc && args.iterations >= 50_000).then(|| {
        ProgressBar::new(args.iterations).with_style(
            ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} walks ({eta})")
                .expect("template is valid"),
        )
    });
    if let Some(b) = &bar {
        b.set_message(format!("{} cost map", graph.behaviour));
    }
    // The graph is this command's own choice (its window and threshold, or the
    // automatic one), so its digest keys the maps.
    let inputs = (graph.params, graph.digest(), &params, [start]);
    let (cache::Cached { mut maps, .. }, origin) = cache::build_or_load(
        args.cache.reuse(cache_dir.as_ref()),
        library.source.fingerprint(),
        &graph.behaviour,
        &inputs,
        || {
            let maps = CostMap::build_from(&graph, &params, &[start], &mut |done| {
                if let Some(b) = &bar {
                    b.set_position(done);
                }
            });
            Ok::<_, std::convert::Infallible>(cache::Cached {
                graph: graph.clone(),
                maps,
                turn: None,
                jumps: Vec::new(),
            })
        },
    )
    .unwrap_or_else(|never| match never {});
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let map = maps.pop().expect("one map per start");
    let from_cache = origin != cache::Origin::Built;
    let elapsed_s = started.elapsed().as_secs_f64();
    tracing::info!(
        from_cache,
        elapsed_s,
        reachable = map.reachable_cells(),
        "cost map ready"
    );
    if let Some(file) = &args.png {
        heatmap::write(&map, file)?;
    }
    let start_node = graph.nodes[map.start_node as usize];
    if args.json {
        let doc = json!({
            "cell_m": map.grid.cell_m,
            "size_m": map.grid.size_m,
            "origin": map.grid.origin().to_array(),
            "fps": map.fps,
            "top_speed_m_s": map.top_speed_m_s,
            "costs": map.rows(),
            "method": map.method,
            "elapsed_s": elapsed_s,
            "from_cache": from_cache,
            "behaviour": map.behaviour,
            "motion_source": library.source.to_string(),
            "start": {
                "given": args.start,
                "node": map.start_node,
                "clip": graph.clip_names[start_node.clip],
                "frame": start_node.frame,
                "root_speed_m_s": root_speed(&start_node),
                "forward_speed_m_s": start_node.forward_speed,
                "lateral_speed_m_s": start_node.lateral_speed,
                "turn_rate_rad_s": start_node.turn_rate,
            },
            "obstacles": map.obstacles,
            "memory_bytes": map.memory_bytes(),
            "convergence": {"points": WATCHED_POINTS, "samples": map.convergence},
        });
        writeln!(out, "{doc}")?;
        return Ok(());
    }
    writeln!(
        out,
        "{} cost map of \"{}\" ({}), {} m × {} m in {} m cells, from {} frame {} ({}: {:.1} m/s forward, {:.1} m/s to the right)",
        map.method.name(),
        map.behaviour,
        library.source,
        figure(map.grid.size_m, 2),
        figure(map.grid.size_m, 2),
        figure(map.grid.cell_m, 3),
        graph.clip_names[start_node.clip],
        start_node.frame,
        args.start,
        start_node.forward_speed,
        start_node.lateral_speed
    )?;
    writeln!(
        out,
        "  reachable cells: {} of {}; {} in {:.3} s; {:.1} KiB",
        map.reachable_cells(),
        map.grid.cells(),
        origin,
        elapsed_s,
        map.memory_bytes() as f64 / 1024.0
    )?;
    for &(x, z) in &[(5.0, 0.0), (-5.0, 0.0), (0.0, -5.0), (0.0, 5.0)] {
        let cost = map
            .cost(DVec2::new(x, z))
            .map_or("unreachable".to_string(), |f| {
                format!(
                    "{} ({:.2} s)",
                    plural(f.into(), "frame"),
                    f as f64 / map.fps
                )
            });
        writeln!(out, "  to ({x:+}, {z:+}): {cost}")?;
    }
    Ok(())
}
