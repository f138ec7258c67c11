//! `fieldhouse capability`: what the basketball agents can do, per behaviour and start
//! state, against grassfire and against what people do.

use super::basketball::CapabilityArgs;
use clap::Args;
use fieldhouse::basketball::human::{self, probe, Check, Stance, SYMMETRY_FRAMES, TARGETS};
use fieldhouse::basketball::{Mover, StateMap};
use fieldhouse::costmap::{root_speed, BuildParams, CostMap, Method};
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
    /// Also measure another behaviour of the motion from its stance (repeatable), such as
    /// a second running subject (run-127), to compare subjects for a role.
    #[arg(long, value_name = "BEHAVIOUR")]
    capture: Vec<String>,
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

fn behaviour_json(mover: &Mover) -> Value {
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
    json!({
        "behaviour": mover.behaviour,
        "window": g.params.window,
        "threshold_m": g.params.threshold_m,
        "top_speed_m_s": g.stats.top_speed_m_s,
        "transition_p95_m": g.stats.transition_p95_m,
        "transition_worst_m": g.stats.transition_worst_m,
        "foot_slide_p95_m": g.stats.foot_slide_p95_m,
        "root_accel_p95_m_s2": g.stats.root_accel_p95_m_s2,
        "capture_root_accel_p95_m_s2": g.stats.capture_root_accel_p95_m_s2,
        "nodes": g.node_count(),
        "clips": g.coverage,
        "jumps_cut": mover.jumps,
        "horizon_frames": mover.map().depth,
        "states": mover.states.iter().map(|s| state_json(mover, s, &grassfire)).collect::<Vec<_>>(),
    })
}

pub(super) fn run(args: CapabilityCmdArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let library = args.capability.library()?;
    for name in &args.capture {
        anyhow::ensure!(
            library.behaviours().contains(&name.as_str()),
            "no behaviour \"{name}\" in {}; it has: {}",
            library.source,
            library.behaviours().join(", ")
        );
    }
    let caps = args.capability.build_with(&library, &args.capture)?;
    let movers = [&caps.dribble, &caps.run, &caps.defense];
    // Other subjects, each measured from its stance against every target's measure.
    let captures: Vec<Value> = caps
        .captures
        .iter()
        .map(|m| {
            let stance = Stance::of(m);
            json!({
                "behaviour": m.behaviour,
                "window": m.graph.params.window,
                "threshold_m": m.graph.params.threshold_m,
                "stance_m_s": root_speed(&m.graph.nodes[stance.map.start_node as usize]),
                "frames": human::measure_all(&stance).into_iter().map(|(k, f)| (k.to_string(), json!(f))).collect::<Map<_, _>>(),
            })
        })
        .collect();
    let behaviours: Vec<Value> = movers.iter().map(|m| behaviour_json(m)).collect();
    let fps = caps.run.map().fps;
    let stances: Vec<Stance> = movers.iter().map(|m| Stance::of(m)).collect();
    let checks = human::check(&stances, fps);
    let symmetry: Vec<Value> = human::symmetry(&stances)
        .into_iter()
        .map(|(behaviour, d, left, right)| {
            json!({
                "behaviour": behaviour,
                "distance_m": d,
                "left_frames": left,
                "right_frames": right,
                "within": left.zip(right).is_some_and(|(l, r)| l.abs_diff(r) <= SYMMETRY_FRAMES),
            })
        })
        .collect();
    if args.json {
        let doc = json!({
            "fps": fps,
            "motion_source": caps.source.to_string(),
            "behaviours": behaviours,
            "targets": checks,
            "stance_below_m_s": human::STANCE_M_S,
            "symmetry": symmetry,
            "symmetry_frames": SYMMETRY_FRAMES,
            "captures": captures,
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
    print_targets(out, &checks, fps)?;
    for c in &captures {
        let f = &c["frames"];
        writeln!(
            out,
            "  {} (from a stance at {:.2} m/s): {}",
            c["behaviour"].as_str().unwrap_or(""),
            c["stance_m_s"].as_f64().unwrap_or(0.0),
            TARGETS
                .iter()
                .map(|t| format!("{} {}", t.what, cell(&f[t.key])))
                .collect::<Vec<_>>()
                .join(", ")
        )?;
    }
    writeln!(
        out,
        "\nleft against right from each stance (within {SYMMETRY_FRAMES} frames):"
    )?;
    for s in &symmetry {
        writeln!(
            out,
            "  {:<8} {} m: left {}, right {}{}",
            s["behaviour"].as_str().unwrap_or(""),
            s["distance_m"],
            cell(&s["left_frames"]),
            cell(&s["right_frames"]),
            if s["within"].as_bool() == Some(true) {
                ""
            } else {
                "  (not symmetric)"
            }
        )?;
    }
    Ok(())
}

/// The targets against people, each with its source; a target not met shows the walk
/// the behaviour takes (the clips it plays), which says what motion is missing.
fn print_targets(out: &mut impl Write, checks: &[Check], fps: f64) -> anyhow::Result<()> {
    writeln!(
        out,
        "\nfrom a stance (slower than {} m/s), against people:",
        human::STANCE_M_S
    )?;
    for c in checks {
        let took = c.frames.map_or("beyond the horizon".to_string(), |f| {
            format!("{:.2} s ({f} frames)", f64::from(f) / fps)
        });
        writeln!(
            out,
            "  {:<8} {:<32} {:<22} target ≤ {} s, people {} s  {}",
            c.behaviour,
            c.what,
            took,
            c.target_s,
            c.people,
            if c.met { "met" } else { "NOT MET" }
        )?;
        if c.state_speed_m_s >= human::STANCE_M_S {
            writeln!(
                out,
                "           from {} at {:.2} m/s: the capture has no stance",
                c.state, c.state_speed_m_s
            )?;
        }
        if !c.met && !c.walk.is_empty() {
            let walk: Vec<String> = c
                .walk
                .iter()
                .map(|(clip, f)| format!("{clip} {f}"))
                .collect();
            writeln!(out, "           the walk: {}", walk.join(" → "))?;
        }
    }
    writeln!(out, "sources:")?;
    for t in &TARGETS {
        writeln!(out, "  {} ({} s): {}", t.what, t.people, t.source)?;
    }
    Ok(())
}
