//! Basketball players stay on the court: every agent-frame of long headless runs of every
//! shipped basketball scenario, on the embedded capture and on a sparse capture of a
//! user's, is inside the court's lines for the ball handler and within the run-off
//! (`basketball::RUN_OFF_M`, 1 m beyond the lines) for everyone else. The replay's own frames are
//! read back, so this checks what spectators see.

use crate::common;

use common::{json, repository_mocap};
use fieldhouse::basketball::RUN_OFF_M;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The millimetre positions are rounded to on the wire.
const ROUNDING_M: f64 = 0.001;
/// How far beyond the lines a player without the ball may be, m: the game's run-off.
const BEYOND_M: f64 = RUN_OFF_M + ROUNDING_M;
/// The ball handler's allowance: only the rounding.
const ON_THE_LINE_M: f64 = ROUNDING_M;
/// Possessions per run: long enough that every start region and every way a possession
/// ends comes up many times.
const POSSESSIONS: i64 = 300;

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("court-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every shipped basketball scenario, as TOML tables.
fn basketball_scenarios() -> Vec<(String, toml::Table)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut found: Vec<(String, toml::Table)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| {
            let table: toml::Table = std::fs::read_to_string(&p).unwrap().parse().unwrap();
            (p.file_stem().unwrap().to_string_lossy().into_owned(), table)
        })
        .filter(|(_, t)| t["sport"].as_str() == Some("basketball"))
        .collect();
    found.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(found.len() >= 3, "shipped basketball scenarios: {found:?}");
    found
}

/// Plays `scenario` headless for [`POSSESSIONS`] and checks every frame of its replay.
fn assert_stays_on_court(name: &str, mut scenario: toml::Table, extra: &str) {
    let dir = scratch(name);
    scenario.remove("duration_s");
    scenario
        .entry("options")
        .or_insert_with(|| toml::Table::new().into())
        .as_table_mut()
        .unwrap()
        .insert("possessions".into(), POSSESSIONS.into());
    let file = dir.join("scenario.toml");
    std::fs::write(&file, toml::to_string(&scenario).unwrap()).unwrap();
    let replay = dir.join("replay.jsonl");
    json(&format!(
        "run {} --bots builtin --out {} --json --cache-dir {} {extra}",
        file.display(),
        replay.display(),
        Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join("basketball-cache")
            .display()
    ));
    let text = std::fs::read_to_string(&replay).unwrap();
    let mut records = text
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap());
    let header = records.next().unwrap();
    let court = &header["match"]["field"]["court"];
    let (length, half_width) = (
        court["length_m"].as_f64().unwrap(),
        court["width_m"].as_f64().unwrap() / 2.0,
    );
    let beyond = |x: f64, z: f64| (-x).max(x - length).max(z.abs() - half_width);
    let (mut frames, mut worst_handler, mut worst_other) = (0, f64::MIN, f64::MIN);
    for frame in records.filter(|r| r["type"] == "frame") {
        frames += 1;
        let holder = frame["ball"]["holder"].as_str();
        for agent in frame["agents"].as_array().unwrap() {
            let p = &agent["position"];
            let out = beyond(p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
            let (allowed, worst) = if holder == agent["id"].as_str() {
                (ON_THE_LINE_M, &mut worst_handler)
            } else {
                (BEYOND_M, &mut worst_other)
            };
            *worst = worst.max(out);
            assert!(
                out <= allowed,
                "{name}: {} at ({}, {}) is {out:.3} m beyond the lines at tick {} \
                 (allowed {allowed} m{})",
                agent["id"],
                p[0],
                p[1],
                frame["tick"],
                if allowed == ON_THE_LINE_M {
                    " with the ball"
                } else {
                    ""
                }
            );
        }
    }
    assert!(frames > 10_000, "{name}: only {frames} frames");
    eprintln!(
        "{name}: {frames} frames; furthest beyond the lines: {worst_handler:.3} m with the \
         ball, {worst_other:.3} m without"
    );
}

#[test]
fn every_shipped_basketball_scenario_stays_on_the_court() {
    for (name, scenario) in basketball_scenarios() {
        assert_stays_on_court(&name, scenario, "");
    }
}

#[test]
fn running_defenders_and_a_sparse_user_capture_stay_on_the_court_too() {
    let (_, mut scenario) = basketball_scenarios()
        .into_iter()
        .find(|(name, _)| name == "basketball-papers-costmap")
        .expect("the papers' cost-map scenario ships");
    // The defender runs instead of its footwork.
    for agent in scenario["agents"].as_array_mut().unwrap() {
        if agent["team"].as_str() == Some("defense") {
            agent
                .as_table_mut()
                .unwrap()
                .insert("strategy".into(), "run".into());
        }
    }
    assert_stays_on_court("defender-runs", scenario.clone(), "");
    // One clip per behaviour: graphs with few ways to turn.
    let capture = scratch("sparse-capture-files");
    for (behaviour, clip) in [
        ("run", "16_36"),
        ("dribble", "06_02"),
        ("defense", "102_08"),
    ] {
        std::fs::create_dir_all(capture.join(behaviour)).unwrap();
        std::fs::copy(
            repository_mocap()
                .join(behaviour)
                .join(format!("{clip}.bvh")),
            capture.join(behaviour).join(format!("{clip}.bvh")),
        )
        .unwrap();
    }
    assert_stays_on_court(
        "sparse-capture",
        scenario,
        &format!("--mocap {}", capture.display()),
    );
}
