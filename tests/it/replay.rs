//! Headless runs and replay files through the binary: determinism, verification,
//! truncation, bad scenarios; and replays the server records, lists and plays.

use crate::common;

use common::{assert_reads_well, bad_input, exits, failure, fieldhouse, json};
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

/// A replay's lines, decompressed if it is in format 2.
fn lines(path: &Path) -> Vec<String> {
    let (text, problem) = fieldhouse::replay::decode(&std::fs::read(path).unwrap()).unwrap();
    assert_eq!(problem, None);
    String::from_utf8(text)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn the_same_scenario_twice_gives_the_same_frames_and_verifies() {
    let dir = scratch("twice");
    let (a, doc) = run(&dir, FIELDERS, "a.jsonl.zst");
    let (b, _) = run(&dir, FIELDERS, "b.jsonl.zst");
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
/// What `replay verify` of a file cut at its end prints: exit code 3, the readable part
/// verified.
fn verified_cut(command_line: &str) -> String {
    let (stdout, stderr) = exits(command_line, 3);
    assert!(stderr.contains("is cut at its end"), "{stderr}");
    stdout
}

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
    let (file, _) = run(&dir, FIELDERS, "a.jsonl.zst");
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
    let (file, doc) = run(&dir, &one_ball, "one.jsonl.zst");
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
        dir.join("again.jsonl.zst").display()
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
    let (file, _) = run(&dir, FIELDERS, "a.jsonl.zst");
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
    // Format 1, as `--out` names it.
    let (file, _) = run(&dir, FIELDERS, "a.jsonl");
    let bytes = std::fs::read(&file).unwrap();
    let cut = bytes.len() * 2 / 3;
    let whole_lines_before = bytes[..cut].iter().filter(|&&b| b == b'\n').count();
    let torn = dir.join("torn.jsonl");
    std::fs::write(&torn, &bytes[..cut]).unwrap();
    let info = json(&format!("replay info {} --json", torn.display()));
    assert_eq!(info["complete"], false);
    assert_eq!(info["damaged"], false);
    // Every complete line but the header is a frame here (no bots, no footer yet).
    assert_eq!(
        info["frames"].as_u64().unwrap() as usize,
        whole_lines_before - 1
    );
    assert!(info["problem"].as_str().unwrap().contains("torn"), "{info}");
    // The readable part still re-simulates exactly, and the exit code says it is cut.
    let verified = verified_cut(&format!("replay verify {}", torn.display()));
    assert!(verified.contains("verified"), "{verified}");
    // A whole line in the middle that is not a record is damage, not a cut: verify fails
    // and names the line.
    let mut lines: Vec<&[u8]> = bytes.split_inclusive(|&b| b == b'\n').collect();
    let middle = lines.len() / 2;
    lines[middle] = b"{\"type\": \"frame\", oops\n";
    let damaged = dir.join("damaged.jsonl");
    std::fs::write(&damaged, lines.concat()).unwrap();
    let (_, err) = exits(&format!("replay verify {}", damaged.display()), 1);
    assert!(
        err.contains("is damaged") && err.contains(&format!("line {}", middle + 1)),
        "{err}"
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
        let err = bad_input(&format!("run {} --out {}", file.display(), out.display()));
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
    let err = bad_input(&format!(
        "run {} --out {}",
        file.display(),
        dir.join("x.jsonl").display()
    ));
    assert!(err.contains("--bots builtin"), "{err}");
    let replay = dir.join("hoops.jsonl.zst");
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
/// JSON values and rounded afterwards) and before replays were compressed, kept as they
/// were written (tests/fixtures/README.md). Every sport plays differently since then
/// (fielders fit the ball's path since simulation version 2, and perceive from angles
/// since version 4; basketball moves with more of the capture since version 3): the
/// files still read, and verifying them names the version change, not only the first
/// frame that differs.
#[test]
fn replays_recorded_by_an_older_release_still_read_and_say_which_simulation_they_need() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    for (file, frames) in [
        ("protocol-2/basketball.jsonl", 121),
        ("protocol-2/baseball.jsonl", 121),
        ("protocol-2/cricket.jsonl", 121),
        ("replay-format1.jsonl", 91),
    ] {
        let path = dir.join(file);
        let out = fieldhouse(&format!("replay verify {}", path.display()));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{file}");
        assert!(
            err.contains("recorded by simulation version 1 and this build simulates version 4"),
            "{file}: {err}"
        );
        let info = stdout(&format!("replay info {}", path.display()));
        assert!(info.contains(&format!("{frames} frames")), "{file}: {info}");
    }
}

/// Protocol 3's frames carry each player's blend across cuts: two minutes of the
/// default basketball match at the demo's 30 frames a second stay within 1 KB a frame,
/// the header names the protocol, and verification writes frames in the version the
/// header names (a file claiming protocol 2 has frames version 2 never wrote).
#[test]
fn basketball_frames_carry_pose_blends_within_a_kilobyte_in_the_version_recorded() {
    let dir = scratch("protocol-3");
    let scenario = "sport = \"basketball\"\nseed = 7\nduration_s = 120.0\nframe_hz = 30.0\n";
    let (replay, _) = run(&dir, scenario, "basketball.jsonl");
    let lines = lines(&replay);
    let header: Value = serde_json::from_str(&lines[0]).unwrap();
    assert_eq!(header["protocol"], 3);
    let frames: Vec<&String> = lines
        .iter()
        .filter(|l| l.starts_with("{\"type\":\"frame\""))
        .collect();
    assert_eq!(frames.len(), 3601);
    let largest = frames.iter().map(|f| f.len()).max().unwrap();
    assert!(largest <= 1024, "a frame of {largest} bytes");
    assert!(frames.iter().filter(|f| f.contains("\"blend\":[")).count() > frames.len() / 2);
    common::assert_verifies(&replay);
    // The same file under a header without `protocol` (as version 2 wrote them) is
    // re-simulated as version 2 frames, which have no blend: the first blend differs.
    let mut old = header.clone();
    old.as_object_mut().unwrap().remove("protocol");
    let claimed = dir.join("claimed-protocol-2.jsonl");
    let body: Vec<&str> = lines[1..].iter().map(String::as_str).collect();
    std::fs::write(&claimed, format!("{old}\n{}\n", body.join("\n"))).unwrap();
    let err = failure(&format!("replay verify {}", claimed.display()));
    assert!(err.contains("].blend differs"), "{err}");
}

/// The zstd frames of a format 2 file, as zstd itself finds them: each one's offset and
/// length (the trailer, a skippable frame, last).
fn zstd_frames(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut frames = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let len = zstd::zstd_safe::find_frame_compressed_size(&bytes[at..]).unwrap();
        frames.push((at, len));
        at += len;
    }
    frames
}

/// How many frame lines zstd finds in `bytes` (whole zstd frames).
fn frame_lines(bytes: &[u8]) -> usize {
    let text = String::from_utf8(zstd::decode_all(bytes).unwrap()).unwrap();
    text.lines()
        .filter(|l| l.starts_with("{\"type\":\"frame\""))
        .count()
}

#[test]
fn a_compressed_replay_is_over_six_times_smaller_than_the_plain_one_and_reads_the_same() {
    let dir = scratch("compressed");
    let (zst, _) = run(&dir, FIELDERS, "a.jsonl.zst");
    // A name ending in .jsonl asks for format 1, plain lines.
    let (plain, _) = run(&dir, FIELDERS, "a.jsonl");
    let (zb, pb) = (std::fs::read(&zst).unwrap(), std::fs::read(&plain).unwrap());
    assert_eq!(zb[..4], [0x28, 0xb5, 0x2f, 0xfd], "a zstd frame");
    assert_eq!(pb[0], b'{');
    let ratio = pb.len() as f64 / zb.len() as f64;
    eprintln!(
        "30 s of two fielders: {} bytes plain, {} compressed ({ratio:.1}×)",
        pb.len(),
        zb.len()
    );
    assert!(ratio >= 6.0, "only {ratio:.2}× smaller");
    // zstd itself (zstdcat) reads the lines out of it, skipping the trailer: the same
    // lines as the plain file's but for the header's format and start time.
    let text = String::from_utf8(zstd::decode_all(&zb[..]).unwrap()).unwrap();
    let (zl, pl): (Vec<&str>, Vec<String>) = (text.lines().collect(), lines(&plain));
    assert_eq!(zl.len(), pl.len());
    assert_eq!(zl[1..], pl[1..]);
    let (zh, ph): (Value, Value) = (
        serde_json::from_str(zl[0]).unwrap(),
        serde_json::from_str(&pl[0]).unwrap(),
    );
    assert_eq!(
        (zh["format"].as_u64(), ph["format"].as_u64()),
        (Some(2), Some(1))
    );
    assert_eq!(zh["scenario"], ph["scenario"]);
    // The header and the footer are chunks of their own; the trailer is 20 bytes.
    let frames = zstd_frames(&zb);
    let chunk = |k: usize| {
        let (at, len) = frames[k];
        String::from_utf8(zstd::decode_all(&zb[at..at + len]).unwrap()).unwrap()
    };
    assert_eq!(chunk(0), format!("{}\n", zl[0]));
    let n = frames.len();
    assert_eq!(chunk(n - 2), format!("{}\n", zl[zl.len() - 1]));
    assert_eq!(frames[n - 1].1, 20);
    assert!(chunk(n - 1).is_empty(), "the trailer is skipped");
    // Chunks of about 60 lines.
    assert_eq!(chunk(1).lines().count(), 60);
    // info, export and verify give the same either way.
    let info = |f: &Path| {
        let mut doc = json(&format!("replay info {} --json", f.display()));
        doc["format"] = Value::Null;
        doc
    };
    assert_eq!(info(&zst), info(&plain));
    assert_eq!(info(&zst)["complete"], true);
    for format in ["csv", "jsonl"] {
        let export = |f: &Path| stdout(&format!("replay export {} --format {format}", f.display()));
        assert_eq!(export(&zst), export(&plain));
    }
    for file in [&zst, &plain] {
        let verified = stdout(&format!("replay verify {}", file.display()));
        assert!(verified.contains("re-simulate identically"), "{verified}");
    }
    // Without --out: the scenario's name with .jsonl.zst, in format 2.
    let ran = std::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(["run", "scenario.toml"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        ran.status.success(),
        "{}",
        String::from_utf8_lossy(&ran.stderr)
    );
    let default = std::fs::read(dir.join("scenario.jsonl.zst")).unwrap();
    assert_eq!(default[..4], zb[..4]);
    let help = stdout("run --help");
    assert!(
        help.contains(".jsonl.zst") && help.contains("format 1"),
        "{help}"
    );
}

#[test]
fn a_compressed_replay_cut_anywhere_reads_to_its_last_whole_chunk_and_that_verifies() {
    let dir = scratch("compressed-cut");
    let (file, _) = run(&dir, FIELDERS, "a.jsonl.zst");
    let bytes = std::fs::read(&file).unwrap();
    let frames = zstd_frames(&bytes);
    let n = frames.len();
    assert!(n > 10, "{n} chunks");
    let end = |k: usize| frames[k].0 + frames[k].1;
    let (footer, trailer) = (frames[n - 2].0, frames[n - 1].0);
    // (cut at, what the problem says, if anything)
    let cuts = [
        (frames[1].0 + frames[1].1 / 2, Some("torn")),
        (frames[n / 2].0, None),
        (frames[n / 2].0 + 3, Some("torn")),
        (frames[n / 2].0 + 7, Some("torn")),
        (end(n - 3) - 1, Some("torn")),
        (footer, None),
        (footer + 5, Some("torn")),
        (trailer, Some("trailer")),
        (trailer + 10, Some("torn")),
        (bytes.len() - 1, Some("torn")),
    ];
    let cut_file = dir.join("cut.jsonl.zst");
    for (cut, problem) in cuts {
        std::fs::write(&cut_file, &bytes[..cut]).unwrap();
        let whole = frames
            .iter()
            .map(|&(at, len)| at + len)
            .filter(|&e| e <= cut)
            .max();
        let info = json(&format!("replay info {} --json", cut_file.display()));
        assert_eq!(info["complete"], false, "cut at {cut}: {info}");
        assert_eq!(
            info["frames"].as_u64().unwrap() as usize,
            frame_lines(&bytes[..whole.unwrap()]),
            "cut at {cut}: {info}"
        );
        match problem {
            None => assert!(info["problem"].is_null(), "cut at {cut}: {info}"),
            Some(said) => assert!(
                info["problem"].as_str().unwrap().contains(said),
                "cut at {cut}: {info}"
            ),
        }
        let verified = verified_cut(&format!("replay verify {}", cut_file.display()));
        assert!(
            verified.contains("the file is incomplete; its readable part was checked"),
            "cut at {cut}: {verified}"
        );
    }
    // Cut in its header's chunk, it is no replay.
    std::fs::write(&cut_file, &bytes[..frames[0].1 - 1]).unwrap();
    let err = failure(&format!("replay info {}", cut_file.display()));
    assert!(
        err.contains("not a fieldhouse replay") && err.contains("torn"),
        "{err}"
    );
}

#[test]
fn a_corrupt_chunk_ends_the_readable_part_and_a_file_of_neither_format_is_refused() {
    let dir = scratch("compressed-corrupt");
    let (file, _) = run(&dir, FIELDERS, "a.jsonl.zst");
    let mut bytes = std::fs::read(&file).unwrap();
    let frames = zstd_frames(&bytes);
    let k = frames.len() / 2;
    let (at, len) = frames[k];
    bytes[at + len / 2] ^= 0xff;
    let bad = dir.join("bad.jsonl.zst");
    std::fs::write(&bad, &bytes).unwrap();
    let info = json(&format!("replay info {} --json", bad.display()));
    assert_eq!(info["complete"], false);
    assert_eq!(
        info["frames"].as_u64().unwrap() as usize,
        frame_lines(&bytes[..at])
    );
    let problem = info["problem"].as_str().unwrap();
    assert!(
        problem.starts_with(&format!("chunk {} (byte {at}): ", k + 1)),
        "{problem}"
    );
    assert_eq!(info["damaged"], true);
    let said = stdout(&format!("replay info {}", bad.display()));
    assert!(said.contains("DAMAGED: chunk"), "{said}");
    // Damage with more of the file after it is not a cut tail: verify fails, naming the
    // chunk and its byte.
    let (_, err) = exits(&format!("replay verify {}", bad.display()), 1);
    assert!(
        err.contains("is damaged") && err.contains(&format!("chunk {} (byte {at})", k + 1)),
        "{err}"
    );
    // Neither JSON lines nor zstd, whatever its name.
    for (name, content) in [
        ("binary.jsonl.zst", &b"\x00\x01\x02\x03 not a replay"[..]),
        ("binary.jsonl", &b"PK\x03\x04 a zip"[..]),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, content).unwrap();
        let err = failure(&format!("replay info {}", path.display()));
        assert!(
            err.contains("not a fieldhouse replay: neither JSON lines (format 1) nor chunked zstd (format 2)"),
            "{err}"
        );
    }
    let empty = dir.join("empty.jsonl.zst");
    std::fs::write(&empty, b"").unwrap();
    assert!(failure(&format!("replay info {}", empty.display())).contains("the file is empty"));
}

#[test]
fn a_replay_written_before_format_2_still_reads() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/replay-format1.jsonl");
    let info = json(&format!("replay info {} --json", fixture.display()));
    assert_eq!(info["format"], 1);
    assert_eq!(info["frames"], 91);
    assert_eq!(info["complete"], true);
    assert_eq!(info["hash_ok"], true);
    let frames: Vec<String> = std::fs::read_to_string(&fixture)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("{\"type\":\"frame\""))
        .map(str::to_string)
        .collect();
    let jsonl = stdout(&format!(
        "replay export {} --format jsonl",
        fixture.display()
    ));
    assert_eq!(jsonl.lines().collect::<Vec<_>>(), frames);
    let csv = stdout(&format!("replay export {}", fixture.display()));
    assert_eq!(csv.lines().count(), 1 + 2 * frames.len());
}

/// `replay paths` on a run whose answers are known in closed form: the fielder runs a
/// half circle of radius 5 m from (50, −5) to (50, 5), bulging away from home plate,
/// while the ball stays 30 m from it straight toward home, its elevation's tangent rising
/// at a constant rate. The bulge is −0.5 and the run 5π m; a constant rate gives no
/// drift; the ball always dead ahead, on the line to home, puts the image on one
/// vertical line (no bend); and the line of sight turns as the fielder's bearing from
/// home does.
#[test]
fn paths_measure_a_run_known_in_closed_form() {
    let dir = scratch("paths-closed-form");
    let (recorded, _) = run(&dir, FIELDERS, "recorded.jsonl");
    let header = lines(&recorded).remove(0);
    let mut text = header + "\n";
    let ticks = 120;
    for k in 0..=ticks {
        let s = k as f64 / ticks as f64;
        let theta = std::f64::consts::PI * s;
        let (x, z) = (50.0 + 5.0 * theta.sin(), -5.0 * theta.cos());
        let height = 1.7 + 30.0 * (0.1 + 0.2 * s);
        let ahead = 30.0 / x.hypot(z);
        let (ball_x, ball_z) = (x - ahead * x, z - ahead * z);
        let mut events = vec![];
        if k == 0 {
            events.push(serde_json::json!({"kind": "launch", "ball": 1,
                "launch": {"speed_m_s": 30.0}, "landing": [20.0, 5.0]}));
        }
        if k == ticks {
            events.push(
                serde_json::json!({"kind": "caught", "ball": 1, "by": "chapman",
                "at": [x, z], "flight_time_s": s}),
            );
        }
        let frame = serde_json::json!({"type": "frame", "match": "a", "tick": k,
            "time_s": s, "ball": {"position": [ball_x, height, ball_z], "state": "flight"},
            "agents": [{"id": "chapman", "position": [x, z], "heading": 0.0, "speed": 0.0}],
            "score": {}, "events": events});
        text += &format!("{frame}\n");
    }
    let file = dir.join("half-circle.jsonl");
    std::fs::write(&file, text).unwrap();
    let doc = json(&format!("replay paths {} --json", file.display()));
    let runs = doc["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 1, "{doc}");
    let r = &runs[0];
    assert_eq!(
        (r["agent"].as_str(), r["ball"].as_u64()),
        (Some("chapman"), Some(1))
    );
    assert_eq!(r["caught"], true);
    assert_eq!(r["shape"], "bulges_away_from_home");
    let close = |key: &str, expected: f64, tolerance: f64| {
        let got = r[key].as_f64().unwrap_or_else(|| panic!("{key}: {r}"));
        assert!(
            (got - expected).abs() < tolerance,
            "{key}: {got}, not {expected}"
        );
    };
    close("bulge", -0.5, 1e-3);
    close("run_m", 5.0 * std::f64::consts::PI, 1e-2);
    close("rate_drift", 0.0, 1e-9);
    // The last look is the frame before the catch's: in a recorded match the ball is
    // already dead in that one's frame, where the run only ends.
    let bearing = |k: f64| {
        let theta = std::f64::consts::PI * k / ticks as f64;
        (-5.0 * theta.cos()).atan2(50.0 + 5.0 * theta.sin())
    };
    let sweep = (bearing(ticks as f64 - 1.0) - bearing(0.0)).to_degrees();
    close("bearing_sweep_deg", sweep, 1e-6);
    close("image_bend", 0.0, 1e-6);
    assert_eq!(doc["fielders"]["chapman"]["catch_rate"], 1.0);
}

/// On a real run, `replay paths` finds every fielder under every ball, and its catches
/// are the ones the match's own score counted.
#[test]
fn paths_count_the_catches_the_score_counts() {
    let dir = scratch("paths-score");
    let every_tick = FIELDERS.replace("seed = 5", "seed = 5\nframe_hz = 60.0");
    let (file, doc) = run(&dir, &every_tick, "fielders.jsonl.zst");
    let paths = json(&format!("replay paths {} --json", file.display()));
    let runs = paths["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2 * 3, "two fielders under three balls: {paths}");
    let caught = runs.iter().filter(|r| r["caught"] == true).count() as u64;
    assert_eq!(Some(caught), doc["result"]["caught"].as_u64(), "{paths}");
    for r in runs {
        assert!(
            r["run_m"].as_f64().unwrap() > 1.0,
            "every fielder runs: {r}"
        );
    }
    let table = stdout(&format!("replay paths {}", file.display()));
    assert!(table.contains("3 finished balls"), "{table}");
    assert!(
        table.contains("chapman") && table.contains("lot-optical"),
        "{table}"
    );
    assert_reads_well(&table);
    let err = failure(&format!(
        "replay paths {}",
        dir.join("absent.jsonl").display()
    ));
    assert!(err.contains("absent.jsonl"), "{err}");
}

/// Every shipped scenario can be run headless. Those written for the server, which plays
/// until a match is deleted, are refused without an end with a message naming the flags
/// that give one, and run with them; `--possessions` ends a basketball game and a flag's
/// value is held to the scenario field's own rules.
#[test]
fn every_shipped_scenario_runs_headless_given_an_end() {
    let dir = scratch("shipped-scenarios");
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut without_end = 0;
    for entry in std::fs::read_dir(&shipped).unwrap() {
        let path = entry.unwrap().path();
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        let run = |flags: &str, out: &str| {
            format!(
                "run {} --out {} --bots builtin --json {flags}",
                path.display(),
                dir.join(out).display()
            )
        };
        if fieldhouse(&run("", &format!("{stem}.jsonl.zst")))
            .status
            .success()
        {
            continue;
        }
        without_end += 1;
        let (_, stderr) = exits(&run("", &format!("{stem}-again.jsonl.zst")), 2);
        assert!(
            stderr.contains("needs an end: pass --duration-s"),
            "{stem}: {stderr}"
        );
        let doc = json(&run("--duration-s 5", &format!("{stem}-5s.jsonl.zst")));
        assert_eq!(doc["simulated_s"], 5.0, "{stem}: {doc}");
    }
    assert!(without_end >= 3, "the server's own scenarios have no end");
    let basketball = shipped.join("basketball.toml");
    let doc = json(&format!(
        "run {} --out {} --json --possessions 3",
        basketball.display(),
        dir.join("three.jsonl.zst").display()
    ));
    assert_eq!(doc["result"]["possession"], 3, "{doc}");
    let (_, stderr) = exits(
        &format!(
            "run {} --out {} --duration-s 0",
            basketball.display(),
            dir.join("never.jsonl.zst").display()
        ),
        2,
    );
    assert!(
        stderr.contains("(with --duration-s or --possessions)"),
        "{stderr}"
    );
    assert!(stderr.contains("duration_s"), "{stderr}");
}

/// A replay names its motion as live matches do, in words: basketball's source, and for
/// fly balls that they use none; the header's `motion` keeps the fingerprint that
/// verification checks.
#[test]
fn a_replay_names_its_motion_in_the_words_live_matches_use() {
    let dir = scratch("motion-words");
    for (sport, words) in [
        ("basketball", "CMU motion capture, embedded: "),
        ("baseball", fieldhouse::sim::NO_MOTION),
    ] {
        let scenario = format!("sport = \"{sport}\"\nseed = 1\nduration_s = 2.0\n");
        let (replay, _) = run(&dir, &scenario, &format!("{sport}.jsonl"));
        let header: Value = serde_json::from_str(&lines(&replay)[0]).unwrap();
        let source = header["match"]["motion_source"].as_str().unwrap();
        assert!(source.starts_with(words), "{sport}: {source}");
        let fingerprint = header["motion"].as_str().unwrap();
        match sport {
            "basketball" => assert_eq!(fingerprint.len(), 16, "{header}"),
            _ => assert_eq!(fingerprint, "none"),
        }
    }
}
