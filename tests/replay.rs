//! Headless runs and replay files through the binary: determinism, verification,
//! truncation, bad scenarios; and replays the server records, lists and plays.

mod common;

use common::{assert_reads_well, failure, fieldhouse, json};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A scratch directory under the test target directory, emptied first.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("replay-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const FIELDERS: &str = r#"
name = "two fielders, scripted balls"
sport = "baseball"
seed = 5
duration_s = 30.0
[[agents]]
id = "chapman"
strategy = "chapman"
position = [60.0, 55.0]
[[agents]]
id = "lot-optical"
strategy = "lot-optical"
position = [55.0, 60.0]
limits = { max_speed_m_s = 7.0, max_accel_m_s2 = 4.0 }
[options]
pause_s = 1.0
launches = [
  { time_s = 0.5, speed_m_s = 36.0, elevation_deg = 45.0, azimuth_deg = 44.0, spin_rpm = 2000.0 },
  { time_s = 8.0, speed_m_s = 30.0, elevation_deg = 55.0, azimuth_deg = 47.0 },
  { time_s = 16.0, speed_m_s = 40.0, elevation_deg = 35.0, azimuth_deg = 40.0, spin_rpm = 1500.0 },
]
"#;

fn run(dir: &Path, scenario: &str, out: &str) -> (PathBuf, Value) {
    let file = dir.join("scenario.toml");
    std::fs::write(&file, scenario).unwrap();
    let replay = dir.join(out);
    let doc = json(&format!(
        "run {} --out {} --json --cache-dir {}",
        file.display(),
        replay.display(),
        dir.join("cache").display()
    ));
    (replay, doc)
}

fn lines(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn the_same_scenario_twice_gives_the_same_frames_and_verifies() {
    let dir = scratch("twice");
    let (a, doc) = run(&dir, FIELDERS, "a.jsonl");
    let (b, _) = run(&dir, FIELDERS, "b.jsonl");
    assert_eq!(doc["result"]["balls"], 3, "three scripted balls: {doc}");
    // Frames (and the footer's hash over them) are identical; only the header's wall
    // clock differs.
    let (la, lb) = (lines(&a), lines(&b));
    assert_eq!(la.len(), lb.len());
    assert_eq!(la[1..], lb[1..]);
    let info = json(&format!("replay info {} --json", a.display()));
    assert_eq!(info["complete"], true);
    assert_eq!(info["frames"].as_u64().unwrap() as usize, la.len() - 2);
    assert_eq!(info["hash_ok"], true);
    let out = fieldhouse(&format!("replay verify {}", a.display()));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// stdout of a command that must succeed.
fn stdout(command_line: &str) -> String {
    let out = fieldhouse(command_line);
    assert!(
        out.status.success(),
        "{command_line}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn export_writes_csv_by_default_and_explains_its_formats() {
    let dir = scratch("export");
    let (file, _) = run(&dir, FIELDERS, "a.jsonl");
    let frames: Vec<String> = lines(&file)
        .into_iter()
        .filter(|l| l.starts_with("{\"type\":\"frame\""))
        .collect();
    // No flag: CSV on stdout, the same as --csv and --format csv.
    let csv = stdout(&format!("replay export {}", file.display()));
    assert!(
        csv.starts_with("tick,time_s,agent,x,y,z,heading\n"),
        "{csv}"
    );
    assert_eq!(csv.lines().count(), 1 + 3 * frames.len());
    assert_eq!(
        stdout(&format!("replay export {} --csv", file.display())),
        csv
    );
    assert_eq!(
        stdout(&format!("replay export {} --format csv", file.display())),
        csv
    );
    // jsonl: the frame messages as recorded, one a line.
    let jsonl = stdout(&format!("replay export {} --format jsonl", file.display()));
    assert_eq!(jsonl.lines().collect::<Vec<_>>(), frames);
    let err = failure(&format!("replay export {} --format xml", file.display()));
    assert!(err.contains("csv") && err.contains("jsonl"), "{err}");
    // The help says what each format holds.
    let help = stdout("replay export --help");
    for expected in [
        "--format",
        "csv",
        "jsonl",
        "tick,time_s,agent,x,y,z,heading",
        "heading (radians",
    ] {
        assert!(help.contains(expected), "{expected:?} not in:\n{help}");
    }
}

#[test]
fn run_and_replay_lines_round_their_figures_and_count_in_words() {
    let dir = scratch("words");
    // One ball and no duration: the run ends when the ball is settled, at a time that
    // is no round number of seconds.
    let one_ball = FIELDERS
        .replace("duration_s = 30.0\n", "")
        .replace("time_s = 0.5,", "time_s = 0.52,")
        .replace(
            "  { time_s = 8.0, speed_m_s = 30.0, elevation_deg = 55.0, azimuth_deg = 47.0 },\n",
            "",
        )
        .replace(
            "  { time_s = 16.0, speed_m_s = 40.0, elevation_deg = 35.0, azimuth_deg = 40.0, spin_rpm = 1500.0 },\n",
            "",
        );
    let (file, doc) = run(&dir, &one_ball, "one.jsonl");
    assert_eq!(doc["result"]["balls"], 1, "{doc}");
    let simulated = doc["simulated_s"].as_f64().unwrap().to_string();
    assert!(
        simulated.split('.').nth(1).map_or(0, str::len) > 4,
        "{simulated} s, printed unrounded, would pass for rounded"
    );
    let scenario = dir.join("scenario.toml");
    let ran = stdout(&format!(
        "run {} --out {}",
        scenario.display(),
        dir.join("again.jsonl").display()
    ));
    assert!(ran.contains("\n1 ball: "), "{ran}");
    let info = stdout(&format!("replay info {}", file.display()));
    assert!(info.contains("complete: finished; 1 ball: "), "{info}");
    assert!(info.contains("0 bot log entries"), "{info}");
    let verified = stdout(&format!("replay verify {}", file.display()));
    for text in [&ran, &info, &verified] {
        assert_reads_well(text);
    }
}

#[test]
fn verify_names_the_tick_of_an_altered_frame() {
    let dir = scratch("altered");
    let (file, _) = run(&dir, FIELDERS, "a.jsonl");
    let mut all = lines(&file);
    let k = all.len() / 2;
    let frame: Value = serde_json::from_str(&all[k]).unwrap();
    assert_eq!(frame["type"], "frame");
    let tick = frame["tick"].as_u64().unwrap();
    let mut altered = frame.clone();
    let x = altered["agents"][0]["position"][0].as_f64().unwrap();
    altered["agents"][0]["position"][0] = (x + 0.5).into();
    all[k] = altered.to_string();
    let bad = dir.join("bad.jsonl");
    std::fs::write(&bad, all.join("\n") + "\n").unwrap();
    let err = failure(&format!("replay verify {}", bad.display()));
    assert!(
        err.contains(&format!("tick {tick}")) && err.contains("agents[0].position[0]"),
        "{err}"
    );
}

#[test]
fn a_file_cut_mid_record_reads_to_the_cut_and_is_incomplete() {
    let dir = scratch("cut");
    let (file, _) = run(&dir, FIELDERS, "a.jsonl");
    let bytes = std::fs::read(&file).unwrap();
    let cut = bytes.len() * 2 / 3;
    let whole_lines_before = bytes[..cut].iter().filter(|&&b| b == b'\n').count();
    let torn = dir.join("torn.jsonl");
    std::fs::write(&torn, &bytes[..cut]).unwrap();
    let info = json(&format!("replay info {} --json", torn.display()));
    assert_eq!(info["complete"], false);
    // Every complete line but the header is a frame here (no bots, no footer yet).
    assert_eq!(
        info["frames"].as_u64().unwrap() as usize,
        whole_lines_before - 1
    );
    assert!(info["problem"].as_str().unwrap().contains("torn"), "{info}");
    // The readable part still re-simulates exactly.
    let out = fieldhouse(&format!("replay verify {}", torn.display()));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A file that is not a replay at all is an error, not a panic.
    let junk = dir.join("junk.jsonl");
    std::fs::write(&junk, b"hello\n").unwrap();
    assert!(failure(&format!("replay info {}", junk.display())).contains("not a fieldhouse replay"));
}

#[test]
fn a_bad_scenario_fails_before_anything_runs_naming_the_field() {
    let dir = scratch("bad");
    let file = dir.join("bad.toml");
    let cases = [
        (
            FIELDERS.replace("strategy = \"lot-optical\"", "strategy = \"lott\""),
            "agents[1].strategy: unknown strategy \"lott\"",
        ),
        (
            FIELDERS.replace("elevation_deg = 55.0", "elevation_deg = 95.0"),
            "options.launches[1].elevation_deg",
        ),
        (FIELDERS.replace("seed = 5", "seed = \"five\""), "seed:"),
        (
            FIELDERS.replace("duration_s = 30.0", "duration_s = 30.0\ncolour = \"red\""),
            "colour",
        ),
    ];
    for (text, expected) in cases {
        std::fs::write(&file, text).unwrap();
        let out = dir.join("never.jsonl");
        let err = failure(&format!("run {} --out {}", file.display(), out.display()));
        assert!(err.contains(expected), "expected {expected:?} in {err}");
        assert!(!out.exists(), "a bad scenario wrote a replay");
    }
}

#[test]
fn a_basketball_scenario_with_bots_runs_with_builtin_brains() {
    let dir = scratch("hoops");
    let scenario = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/basketball-bot.toml"),
    )
    .unwrap();
    let file = dir.join("scenario.toml");
    std::fs::write(&file, &scenario).unwrap();
    let err = failure(&format!(
        "run {} --out {}",
        file.display(),
        dir.join("x.jsonl").display()
    ));
    assert!(err.contains("--bots builtin"), "{err}");
    let replay = dir.join("hoops.jsonl");
    let source = format!("--cache-dir {}", dir.join("cache").display());
    let doc = json(&format!(
        "run {} --bots builtin --out {} --json {source}",
        file.display(),
        replay.display()
    ));
    let possessions = doc["result"]["possession"].as_u64().unwrap();
    assert!(possessions >= 1, "{doc}");
    let out = fieldhouse(&format!("replay verify {} {source}", replay.display()));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Replays recorded before the protocol's messages were typed (frames were built as
/// JSON values and rounded afterwards), kept as they were written: the format they are
/// in still reads, and this build writes their frames as the same bytes, so they verify.
#[test]
fn replays_recorded_by_an_older_release_still_verify_byte_for_byte() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/protocol-2");
    for sport in ["baseball", "cricket", "basketball"] {
        let file = dir.join(format!("{sport}.jsonl"));
        let verified = stdout(&format!("replay verify {}", file.display()));
        assert!(
            verified.contains("121 frames over 720 ticks re-simulate identically"),
            "{sport}: {verified}"
        );
    }
}
