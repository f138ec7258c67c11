//! Where motion comes from on the command line (the CMU capture embedded in the binary,
//! or `--mocap DIR` / `FIELDHOUSE_MOCAP_DIR` for a user's own), and `fieldhouse motion-graph`.

use anyhow::Context;
use clap::Args;
use fieldhouse::basketball::capability::HORIZON_FRAMES;
use fieldhouse::basketball::human::{self, Stance};
use fieldhouse::costmap::{
    root_speed, start_states, symmetrise, BuildParams, CostMap, STANDING_MIRRORED,
};
use fieldhouse::motion::{
    quickest_turn_around, GraphParams, Mirroring, MotionGraph, MotionLibrary, AUTO_WINDOWS, FPS,
};
use fieldhouse::words::{figure, plural};
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub(super) struct MotionSourceArgs {
    /// Your own motion capture instead of the CMU capture built into fieldhouse: a
    /// directory with one folder per behaviour (DIR/run/, DIR/dribble/, DIR/defense/) of
    /// BVH files, or of CMU's ASF/AMC files (each NN_MM.amc with the folder's NN.asf).
    /// Default: the CMU capture embedded in the binary (data/mocap in the repository
    /// lists its clips, sources and terms).
    #[arg(long, value_name = "DIR", env = "FIELDHOUSE_MOCAP_DIR")]
    pub mocap: Option<PathBuf>,
    /// Use the clips only as captured. By default every clip is also played mirrored
    /// (left and right exchanged): one take of a movement to one side says what a body
    /// can do to the other, and without it the CMU defender could not slide left.
    #[arg(long)]
    pub no_mirror: bool,
}

impl MotionSourceArgs {
    /// Loads the motion library, logging which source it is and every clip that failed.
    pub(super) fn load(&self) -> anyhow::Result<MotionLibrary> {
        let mirroring = if self.no_mirror {
            Mirroring::Off
        } else {
            Mirroring::On
        };
        let library = match &self.mocap {
            Some(dir) => MotionLibrary::load(dir, FPS, mirroring).with_context(|| {
                format!(
                    "--mocap (or FIELDHOUSE_MOCAP_DIR) {} is not a usable motion directory. \
                     It takes your own capture: one folder per behaviour of BVH files, or of \
                     ASF/AMC files (run/, dribble/, defense/). Leave it out to use the CMU motion capture \
                     built into fieldhouse",
                    dir.display()
                )
            })?,
            None => MotionLibrary::embedded(FPS, mirroring),
        };
        match library.source.dir() {
            // The operator's own log may name the directory; visitors never see it.
            Some(dir) => {
                tracing::info!(source = %library.source, dir = %dir.display(), skipped = library.problems().len(), "motion loaded")
            }
            None => tracing::info!(source = %library.source, "motion loaded"),
        }
        Ok(library)
    }
}

#[derive(Args, Debug, Clone)]
pub(super) struct GraphArgs {
    /// Behaviour (a folder of the motion data): run, dribble, defense, ...
    #[arg(long)]
    pub behaviour: String,
    /// Largest RMS joint distance (metres) a transition may have: lower is smoother,
    /// higher is better connected. Default: of 0.06–0.50 m, the loosest at which every clip
    /// keeps at least half its frames and the cuts accelerate the root no more than the
    /// capture itself does (95th percentiles; --sweep shows every candidate).
    #[arg(long, value_parser = super::args::positive)]
    pub threshold: Option<f64>,
    /// Frames compared on each side of a transition (and blended at playback). Default:
    /// with --threshold, 10 (⅓ s); without, the automatic choice also tries 10, 8 and 6.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=120))]
    pub window: Option<u32>,
    #[command(flatten)]
    pub source: MotionSourceArgs,
}

impl GraphArgs {
    pub(super) fn build(&self) -> anyhow::Result<(MotionLibrary, MotionGraph)> {
        let library = self.source.load()?;
        let owned = library.ground_clips(&self.behaviour);
        let clips: Vec<_> = owned.iter().collect();
        if clips.is_empty() {
            anyhow::bail!(
                "no clips of behaviour \"{}\" in {}; it has: {}",
                self.behaviour,
                library.source,
                library.behaviours().join(", ")
            );
        }
        let window = self.window.map(|w| w as usize);
        let graph = match self.threshold {
            Some(threshold_m) => MotionGraph::build(
                &self.behaviour,
                &clips,
                GraphParams {
                    window: window.unwrap_or(GraphParams::default().window),
                    threshold_m,
                },
            )?,
            None => match window {
                Some(w) => MotionGraph::build_auto(&self.behaviour, &clips, &[w])?,
                None => MotionGraph::build_auto(&self.behaviour, &clips, &AUTO_WINDOWS)?,
            },
        };
        Ok((library, graph))
    }
}

#[derive(Args, Debug)]
#[command(
    about = "Build a behaviour's motion graph and print its size",
    allow_negative_numbers = true,
    args_override_self = true,
    after_help = "Example: fieldhouse motion-graph --behaviour run --json"
)]
pub(super) struct MotionGraphArgs {
    #[command(flatten)]
    graph: GraphArgs,
    /// Build every graph the automatic choice considers (each window and threshold) and
    /// print, for each, what it keeps, how good its cuts are (the blends' foot slide and
    /// root acceleration) and what the behaviour can do from its stance (frames to 1 m
    /// left and right, 5 m ahead and behind, a turn around), so the choice can be seen
    /// against both. Takes a minute or more: each graph gets a cost map.
    #[arg(long, conflicts_with_all = ["threshold", "window"])]
    sweep: bool,
    /// Print one JSON document, with the pruned graph's edges as [from, to] node ids and
    /// each node's [clip, frame].
    #[arg(long)]
    json: bool,
}

pub(super) fn run(args: MotionGraphArgs, out: &mut impl Write) -> anyhow::Result<()> {
    if args.sweep {
        return sweep(&args.graph, args.json, out);
    }
    let (library, graph) = args.graph.build()?;
    let s = &graph.stats;
    if args.json {
        let doc = json!({
            "behaviour": graph.behaviour,
            "motion_source": library.source.to_string(),
            "fps": graph.fps,
            "params": graph.params,
            "frames": s.frames,
            "clips": graph.clip_names,
            "transitions_before_pruning": s.transitions_before_pruning,
            "transitions_after_pruning": s.transitions_after_pruning,
            "largest_scc": s.largest_scc,
            "top_speed_m_s": s.top_speed_m_s,
            "transition_worst_m": s.transition_worst_m,
            "transition_p95_m": s.transition_p95_m,
            "coverage": graph.coverage,
            "nodes": graph.nodes.iter().map(|n| json!([graph.clip_names[n.clip], n.frame])).collect::<Vec<_>>(),
            "edges": graph.edges.iter().map(|e| [e.from, e.to]).collect::<Vec<_>>(),
        });
        writeln!(out, "{doc}")?;
        return Ok(());
    }
    writeln!(
        out,
        "motion graph of \"{}\" from {} at {} fps",
        graph.behaviour, library.source, graph.fps
    )?;
    writeln!(
        out,
        "  clips:        {} ({})",
        s.clips,
        graph.clip_names.join(", ")
    )?;
    writeln!(out, "  frames:       {}", s.frames)?;
    writeln!(
        out,
        "  transitions:  {} found (RMS ≤ {} m over {}), {} kept after pruning",
        s.transitions_before_pruning,
        figure(graph.params.threshold_m, 3),
        plural(graph.params.window as u64, "frame"),
        s.transitions_after_pruning
    )?;
    writeln!(
        out,
        "  largest SCC:  {} of {} frames ({:.0} %)",
        s.largest_scc,
        s.frames,
        100.0 * s.largest_scc as f64 / s.frames as f64
    )?;
    writeln!(
        out,
        "  cuts:         RMS {} m at the 95th percentile, {} m at worst",
        figure(s.transition_p95_m, 3),
        figure(s.transition_worst_m, 3)
    )?;
    writeln!(out, "  edges:        {}", graph.edges.len())?;
    writeln!(
        out,
        "  top speed:    {:.2} m/s (over the frames kept)",
        s.top_speed_m_s
    )?;
    writeln!(
        out,
        "  per clip:     frames kept of frames, transitions in / out"
    )?;
    let name_width = graph
        .coverage
        .iter()
        .map(|c| c.name.len())
        .max()
        .unwrap_or(0);
    for c in &graph.coverage {
        let left_out = if c.joined() {
            String::new()
        } else {
            format!(
                "  (under half: its best transition to another clip is {})",
                c.best_transition_m
                    .map(|d| format!("{} m", figure(d, 3)))
                    .unwrap_or_else(|| "none".into())
            )
        };
        writeln!(
            out,
            "    {:<name_width$} {:>5} of {:<5} {:>4} / {}{left_out}",
            c.name, c.kept, c.frames, c.transitions_in, c.transitions_out
        )?;
    }
    Ok(())
}

/// `motion-graph --sweep`: every candidate graph with its cut quality and what the
/// behaviour can do from its stance, and which one the automatic choice takes.
fn sweep(args: &GraphArgs, json: bool, out: &mut impl Write) -> anyhow::Result<()> {
    let library = args.source.load()?;
    let owned = library.ground_clips(&args.behaviour);
    let clips: Vec<_> = owned.iter().collect();
    anyhow::ensure!(
        !clips.is_empty(),
        "no clips of behaviour \"{}\" in {}",
        args.behaviour,
        library.source
    );
    let chosen = MotionGraph::build_auto(&args.behaviour, &clips, &AUTO_WINDOWS)?.params;
    let mut rows = Vec::new();
    MotionGraph::each_candidate(&args.behaviour, &clips, &AUTO_WINDOWS, |graph| {
        let joined = graph.coverage.iter().filter(|c| c.joined()).count();
        // The stance and, in a mirrored capture, its mirror image (start_states lists
        // them first).
        let states = start_states(&graph);
        let standing = &states[0];
        let stances: Vec<u32> = states
            .iter()
            .take_while(|s| s.name == "standing" || s.name == STANDING_MIRRORED)
            .map(|s| s.node)
            .collect();
        let mut maps = CostMap::build_from(
            &graph,
            &BuildParams {
                depth: HORIZON_FRAMES,
                ..BuildParams::default()
            },
            &stances,
            &mut |_| {},
        );
        if let [stance, twin] = &mut maps[..] {
            symmetrise(&graph, stance, twin);
        }
        let turn = quickest_turn_around(&graph, maps.iter().map(|m| m.start_node));
        let stance = Stance {
            behaviour: &args.behaviour,
            graph: &graph,
            state: &standing.name,
            map: &maps[0],
            twin: maps.get(1),
            turn: turn.as_ref(),
        };
        let s = &graph.stats;
        rows.push(json!({
            "window": graph.params.window,
            "threshold_m": graph.params.threshold_m,
            "chosen": graph.params == chosen,
            "clips_joined": joined,
            "clips": clips.len(),
            "nodes": graph.node_count(),
            "transition_p95_m": s.transition_p95_m,
            "foot_slide_p95_m": s.foot_slide_p95_m,
            "root_accel_p95_m_s2": s.root_accel_p95_m_s2,
            "capture_root_accel_p95_m_s2": s.capture_root_accel_p95_m_s2,
            "stance_m_s": root_speed(&graph.nodes[standing.node as usize]),
            "frames": human::measure_all(&stance).into_iter().map(|(k, f)| (k.to_string(), json!(f))).collect::<serde_json::Map<_, _>>(),
        }));
        std::ops::ControlFlow::Continue(())
    })?;
    if json {
        writeln!(
            out,
            "{}",
            json!({"behaviour": args.behaviour, "motion_source": library.source.to_string(), "candidates": rows})
        )?;
        return Ok(());
    }
    writeln!(
        out,
        "motion graphs of \"{}\" ({}): cut quality against what it can do from its stance (frames at 30 fps; * the automatic choice)",
        args.behaviour, library.source
    )?;
    writeln!(
        out,
        "{:<7} {:>9} {:>7} {:>6} {:>9} {:>14} {:>24} {:>10} {:>7} {:>8} {:>8} {:>9} {:>5}",
        "window",
        "threshold",
        "joined",
        "nodes",
        "RMS p95",
        "foot slide p95",
        "root accel p95 (capture)",
        "stance m/s",
        "left 1m",
        "right 1m",
        "ahead 5m",
        "behind 5m",
        "turn"
    )?;
    // serde_json's values ignore widths, so every field is a plain number or string here.
    let number = |v: &serde_json::Value| v.as_f64().unwrap_or(0.0);
    let frames = |v: &serde_json::Value| v.as_u64().map_or("–".to_string(), |f| f.to_string());
    for r in &rows {
        let f = &r["frames"];
        let chosen = if r["chosen"].as_bool() == Some(true) {
            "*"
        } else {
            " "
        };
        let joined = format!("{}/{}", r["clips_joined"], r["clips"]);
        let accel = format!(
            "{:.1} ({:.1}) m/s²",
            number(&r["root_accel_p95_m_s2"]),
            number(&r["capture_root_accel_p95_m_s2"])
        );
        writeln!(
            out,
            "{chosen}{:<6} {:>9.2} {joined:>7} {:>6} {:>7.3} m {:>12.3} m {accel:>24} {:>10.2} {:>7} {:>8} {:>8} {:>9} {:>5}",
            r["window"].as_u64().unwrap_or(0),
            number(&r["threshold_m"]),
            r["nodes"].as_u64().unwrap_or(0),
            number(&r["transition_p95_m"]),
            number(&r["foot_slide_p95_m"]),
            number(&r["stance_m_s"]),
            frames(&f["left_1m"]),
            frames(&f["right_1m"]),
            frames(&f["ahead_5m"]),
            frames(&f["behind_5m"]),
            frames(&f["turn_around"]),
        )?;
    }
    Ok(())
}
