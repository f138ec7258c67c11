//! `fieldhouse capability`: what the basketball agents can do, per behaviour and start
//! state, against grassfire and against what people do.

use super::basketball::CapabilityArgs;
use clap::Args;
use fieldhouse::basketball::{Mover, StateMap};
use fieldhouse::costmap::{root_speed, BuildParams, CostMap, Method};
use fieldhouse::motion::{Jump, MotionLibrary};
use glam::DVec2;
use serde_json::{json, Map, Value};
use std::io::Write;

#[derive(Args, Debug)]
#[command(
    about = "What the basketball agents can do: frames to reach squares around them, per behaviour and start state",
    after_help = "Squares are the agent's own: +x ahead, +z on its right. A point d metres \
        away counts as reached in the map cell just beyond it (cells of 0.5 m), so 1 m \
        ahead is the cell from 1.0 to 1.5 m.\n\
        Example: fieldhouse capability --json"
)]
pub(super) struct CapabilityCmdArgs {
    #[command(flatten)]
    capability: CapabilityArgs,
    /// Print one JSON document.
    #[arg(long)]
    json: bool,
}

/// The points reported, in the agent's frame (+x ahead, +z right), by their JSON key.
const POINTS: [(&str, f64, f64); 9] = [
    ("ahead_1m", 1.0, 0.0),
    ("ahead_3m", 3.0, 0.0),
    ("ahead_5m", 5.0, 0.0),
    ("left_1m", 0.0, -1.0),
    ("left_3m", 0.0, -3.0),
    ("right_1m", 0.0, 1.0),
    ("right_3m", 0.0, 3.0),
    ("behind_3m", -3.0, 0.0),
    ("behind_5m", -5.0, 0.0),
];

/// What people need, in frames at 30 fps, with where the figure comes from.
const HUMAN: [(&str, u32, &str); 3] = [
    (
        "ahead_5m",
        32,
        "5 m sprint from standing, 1.0–1.1 s (field-sport sprint tests)",
    ),
    (
        "behind_5m",
        60,
        "about half the 5-0-5 agility test (5 m in, 180° turn, 5 m out: 2.2–2.9 s); estimate",
    ),
    (
        "right_1m",
        15,
        "one defensive slide step to either side, about 0.5 s; estimate",
    ),
];

/// The cell a point `d` metres out counts as: the one just beyond it, in the row or
/// column on the +side of the agent's axis.
fn probe(x: f64, z: f64) -> DVec2 {
    const NUDGE: f64 = 0.01;
    DVec2::new(
        x + NUDGE * if x < 0.0 { -1.0 } else { 1.0 },
        z + NUDGE * if z < 0.0 { -1.0 } else { 1.0 },
    )
}

fn frames_to(map: &CostMap) -> Map<String, Value> {
    POINTS
        .iter()
        .map(|&(key, x, z)| (key.to_string(), json!(map.cost(probe(x, z)))))
        .collect()
}

/// Cells whose centre is within `radius` m of the agent that the map does not reach.
fn unreachable_within(map: &CostMap, radius: f64) -> usize {
    (0..map.costs.len())
        .filter(|&c| map.grid.centre(c).length() <= radius && map.costs[c].is_none())
        .count()
}

fn state_json(mover: &Mover, s: &StateMap, grassfire: &CostMap) -> Value {
    let node = mover.graph.nodes[s.state.node as usize];
    json!({
        "name": s.state.name,
        "node": s.state.node,
        "clip": mover.graph.clip_names[node.clip],
        "frame": node.frame,
        "root_speed_m_s": root_speed(&node),
        "frames_to": frames_to(&s.map),
        "grassfire": frames_to(grassfire),
        "reachable_cells": s.map.reachable_cells(),
        "memory_bytes": s.map.memory_bytes(),
        "unreachable_within_3m": unreachable_within(&s.map, 3.0),
    })
}

fn behaviour_json(mover: &Mover, library: &MotionLibrary) -> Value {
    let g = &mover.graph;
    let grassfire = CostMap::build(
        g,
        &BuildParams {
            method: Method::Grassfire,
            grid: mover.map().grid,
            depth: mover.map().depth,
            ..BuildParams::default()
        },
        &mut |_| {},
    );
    let jumps: Vec<Value> = library
        .clips_of(mover.behaviour)
        .filter_map(|c| Jump::find(c).map(|j| json!({"clip": c.name, "jump": j})))
        .collect();
    json!({
        "behaviour": mover.behaviour,
        "window": g.params.window,
        "threshold_m": g.params.threshold_m,
        "top_speed_m_s": g.stats.top_speed_m_s,
        "transition_p95_m": g.stats.transition_p95_m,
        "transition_worst_m": g.stats.transition_worst_m,
        "nodes": g.node_count(),
        "clips": g.coverage,
        "jumps_cut": jumps,
        "horizon_frames": mover.map().depth,
        "states": mover.states.iter().map(|s| state_json(mover, s, &grassfire)).collect::<Vec<_>>(),
    })
}

pub(super) fn run(args: CapabilityCmdArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let library = args.capability.library()?;
    let caps = args.capability.build(&library)?;
    let movers = [&caps.dribble, &caps.run, &caps.defense];
    let behaviours: Vec<Value> = movers.iter().map(|m| behaviour_json(m, &library)).collect();
    if args.json {
        let doc = json!({
            "fps": caps.run.map().fps,
            "motion_source": caps.source.to_string(),
            "behaviours": behaviours,
            "human_reference_frames": HUMAN.iter().map(|(k, f, why)| json!({"key": k, "frames": f, "source": why})).collect::<Vec<_>>(),
        });
        writeln!(out, "{doc}")?;
        return Ok(());
    }
    let cell = |v: &Value| v.as_u64().map_or("–".to_string(), |f| f.to_string());
    writeln!(
        out,
        "frames (30 fps) to reach each square from each start state; grassfire in brackets; – beyond the {}-frame horizon",
        caps.run.map().depth
    )?;
    writeln!(
        out,
        "{:<9} {:<30} {:>5}  {}",
        "behaviour",
        "start state",
        "m/s",
        POINTS
            .iter()
            .map(|(k, _, _)| format!("{k:>13}"))
            .collect::<String>()
    )?;
    for b in &behaviours {
        for s in b["states"].as_array().into_iter().flatten() {
            let row: String = POINTS
                .iter()
                .map(|(k, _, _)| {
                    format!(
                        "{:>13}",
                        format!(
                            "{} ({})",
                            cell(&s["frames_to"][k]),
                            cell(&s["grassfire"][k])
                        )
                    )
                })
                .collect();
            writeln!(
                out,
                "{:<9} {:<30} {:>5.2}  {row}",
                b["behaviour"].as_str().unwrap_or(""),
                s["name"].as_str().unwrap_or(""),
                s["root_speed_m_s"].as_f64().unwrap_or(0.0),
            )?;
        }
    }
    writeln!(
        out,
        "people: {}",
        HUMAN
            .iter()
            .map(|(k, f, why)| format!("{k} ≈ {f} ({why})"))
            .collect::<Vec<_>>()
            .join("; ")
    )?;
    Ok(())
}
