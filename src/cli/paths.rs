//! `fieldhouse replay paths`: the catching theories' signatures of every fielder's run in
//! a recorded fly-ball match, measured from its frames.
//!
//! `catch-sweep` measures the built-in strategies from inside their trials. A bot's brain
//! is out of the server's sight, and so is a learner's; what the match recorded is not:
//! where the ball and every fielder were, frame by frame. Measured from there with the
//! same [`RunWatch`], a bot's runs and a built-in strategy's on the same balls compare
//! like for like.

use fieldhouse::fielding::{RunWatch, SignatureSummary, Signatures};
use fieldhouse::replay::Replay;
use fieldhouse::sim::Sport;
use fieldhouse::words::figure;
use glam::{DVec2, DVec3};
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::io::Write;

/// One fielder's run under one ball.
#[derive(Debug, Serialize)]
struct BallRun {
    ball: u64,
    agent: String,
    /// This fielder caught the ball.
    caught: bool,
    /// How far the fielder ran while the ball flew, m.
    run_m: f64,
    #[serde(flatten)]
    signatures: Signatures,
}

/// A fielder's runs in sum: catches, and the signatures summed as `catch-sweep` sums them.
#[derive(Debug, Serialize)]
struct FielderSummary {
    balls: usize,
    caught: usize,
    catch_rate: f64,
    #[serde(flatten)]
    signatures: SignatureSummary,
    mean_run_m: f64,
}

pub(super) fn paths(replay: &Replay, as_json: bool, out: &mut impl Write) -> anyhow::Result<()> {
    anyhow::ensure!(
        replay.scenario.sport != Sport::Basketball,
        "paths are measured on fly balls (baseball, cricket); this replay is basketball"
    );
    let field = &replay.header["match"]["field"];
    let home = DVec2::new(
        field["home"][0].as_f64().unwrap_or(0.0),
        field["home"][1].as_f64().unwrap_or(0.0),
    );
    let eye = field["eye_height_m"].as_f64().unwrap_or(1.7);
    let runs = runs(replay, home, eye)?;
    let mut by_agent: BTreeMap<&str, Vec<&BallRun>> = BTreeMap::new();
    for run in &runs {
        by_agent.entry(&run.agent).or_default().push(run);
    }
    let summaries: BTreeMap<&str, FielderSummary> = by_agent
        .iter()
        .map(|(agent, runs)| (*agent, summarise(runs)))
        .collect();
    if as_json {
        writeln!(
            out,
            "{}",
            json!({"match": replay.match_id(), "sport": replay.scenario.sport.name(),
                   "fielders": summaries, "runs": runs})
        )?;
        return Ok(());
    }
    let balls = runs.iter().map(|r| r.ball).max().unwrap_or(0);
    writeln!(
        out,
        "{} replay of match {}: {} finished ball{}, measured from {} frames",
        replay.scenario.sport.name(),
        replay.match_id(),
        balls,
        if balls == 1 { "" } else { "s" },
        replay.frames.len()
    )?;
    writeln!(
        out,
        "fielder       balls  caught straight   →home   ←home  bulge  ṙ drift img bend α sweep   run m"
    )?;
    let optional = |x: Option<f64>, digits: usize| x.map_or("-".to_owned(), |x| figure(x, digits));
    for (agent, summary) in &summaries {
        let s = &summary.signatures;
        writeln!(
            out,
            "{agent:<12} {:>6} {:>6.1}% {:>7.0}% {:>6.0}% {:>6.0}% {:>6} {:>8} {:>8} {:>6}° {:>7.1}",
            summary.balls,
            100.0 * summary.catch_rate,
            100.0 * s.share_straight,
            100.0 * s.share_bulging_toward_home,
            100.0 * s.share_bulging_away_from_home,
            s.median_bulge.map_or("-".to_owned(), |b| format!("{b:+.2}")),
            optional(s.median_rate_drift, 3),
            optional(s.median_image_bend, 3),
            optional(s.median_bearing_sweep_deg, 1),
            summary.mean_run_m
        )?;
    }
    writeln!(
        out,
        "(medians over balls; a run lasts from the launch to the catch or the landing; see docs/catching.md)"
    )?;
    Ok(())
}

/// Every fielder's run under every ball that ended in the file, in the file's order. A
/// run is watched on the frames in which the ball flies; frames a recording skipped
/// (`frame_hz` below `tick_hz`) are looks the measures do not get.
fn runs(replay: &Replay, home: DVec2, eye: f64) -> anyhow::Result<Vec<BallRun>> {
    let mut runs = Vec::new();
    let mut flying: Option<(u64, BTreeMap<String, RunWatch>)> = None;
    for (tick, line) in &replay.frames {
        let frame: Value = serde_json::from_str(line)
            .map_err(|e| anyhow::anyhow!("the frame of tick {tick} is not JSON: {e}"))?;
        let fielders: Vec<(&str, DVec2)> = frame["agents"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|a| Some((a["id"].as_str()?, position2(&a["position"])?)))
            .collect();
        for event in frame["events"].as_array().into_iter().flatten() {
            let ball = event["ball"].as_u64().unwrap_or(0);
            match event["kind"].as_str() {
                Some("launch") => flying = Some((ball, BTreeMap::new())),
                Some(kind @ ("caught" | "landed")) => {
                    let Some((number, mut watches)) = flying.take() else {
                        continue; // a ball launched before the file's first frame
                    };
                    for (id, at) in &fielders {
                        if let Some(watch) = watches.get_mut(*id) {
                            watch.arrive(*at);
                        }
                    }
                    let by = (kind == "caught").then(|| event["by"].as_str().unwrap_or(""));
                    runs.extend(watches.into_iter().map(|(agent, watch)| BallRun {
                        ball: number,
                        caught: by == Some(agent.as_str()),
                        run_m: watch.path_length_m(),
                        signatures: watch.signatures(home),
                        agent,
                    }));
                }
                _ => {}
            }
        }
        let Some((_, watches)) = flying.as_mut() else {
            continue;
        };
        if frame["ball"]["state"].as_str() != Some("flight") {
            continue;
        }
        let t = frame["time_s"].as_f64().unwrap_or(0.0);
        let Some(ball) = position3(&frame["ball"]["position"]) else {
            continue;
        };
        for (id, at) in fielders {
            watches
                .entry(id.to_owned())
                .or_default()
                .look(t, ball, at, home, eye);
        }
    }
    Ok(runs)
}

fn position2(v: &Value) -> Option<DVec2> {
    Some(DVec2::new(v[0].as_f64()?, v[1].as_f64()?))
}

fn position3(v: &Value) -> Option<DVec3> {
    Some(DVec3::new(v[0].as_f64()?, v[1].as_f64()?, v[2].as_f64()?))
}

fn summarise(runs: &[&BallRun]) -> FielderSummary {
    let n = runs.len();
    let caught = runs.iter().filter(|r| r.caught).count();
    let signatures: Vec<Signatures> = runs.iter().map(|r| r.signatures).collect();
    FielderSummary {
        balls: n,
        caught,
        catch_rate: caught as f64 / n.max(1) as f64,
        signatures: SignatureSummary::of(&signatures),
        mean_run_m: runs.iter().map(|r| r.run_m).sum::<f64>() / n.max(1) as f64,
    }
}
