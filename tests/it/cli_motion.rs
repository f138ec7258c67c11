//! `fieldhouse motion-graph` and `fieldhouse costmap` on the real CMU motion capture, as a
//! user runs them, and their errors.

use crate::common;

use common::{failure, fieldhouse, json, repository_mocap};
use serde_json::Value;
use std::path::Path;

/// A scratch directory under the system temp dir, removed when dropped.
fn scratch(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("fieldhouse-{name}-"))
        .tempdir()
        .unwrap()
}

#[test]
fn the_motion_graph_of_real_running_is_strongly_connected() {
    let doc = json("motion-graph --behaviour run --json");
    let nodes = doc["nodes"].as_array().unwrap().len();
    assert_eq!(nodes, doc["largest_scc"].as_u64().unwrap() as usize);
    assert!(nodes * 2 >= doc["frames"].as_u64().unwrap() as usize);
    let edges: Vec<(usize, usize)> = doc["edges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e[0].as_u64().unwrap() as usize,
                e[1].as_u64().unwrap() as usize,
            )
        })
        .collect();
    assert!(edges.iter().all(|&(a, b)| a < nodes && b < nodes));
    // Every node reaches every other and is reached by it: search both ways from node 0.
    for forward in [true, false] {
        let mut seen = vec![false; nodes];
        let mut stack = vec![0];
        seen[0] = true;
        while let Some(v) = stack.pop() {
            for &(a, b) in &edges {
                let (from, to) = if forward { (a, b) } else { (b, a) };
                if from == v && !seen[to] {
                    seen[to] = true;
                    stack.push(to);
                }
            }
        }
        assert!(seen.iter().all(|s| *s), "not strongly connected");
    }
    // The clips are CMU subject 16's.
    assert!(doc["clips"]
        .as_array()
        .unwrap()
        .iter()
        .all(|c| c.as_str().unwrap().starts_with("16_")));
}

#[test]
fn the_embedded_capture_is_the_default_and_a_directory_replaces_it() {
    // A clip is a BVH or AMC file; an ASF file is the skeleton of the AMC files beside it.
    let clips_on_disk = |behaviour: &std::path::Path| {
        std::fs::read_dir(behaviour)
            .unwrap()
            .filter(|f| {
                let name = f.as_ref().unwrap().file_name();
                let name = name.to_string_lossy();
                name.ends_with(".bvh") || name.ends_with(".amc")
            })
            .count()
    };
    let all: usize = std::fs::read_dir(repository_mocap())
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.is_dir())
        .map(|behaviour| clips_on_disk(&behaviour))
        .sum();
    let embedded = json("motion-graph --behaviour dribble --json");
    assert_eq!(
        embedded["motion_source"],
        format!("CMU motion capture, embedded: {all} clips and their mirror images")
    );
    assert_eq!(
        embedded["clips"].as_array().unwrap().len(),
        2 * clips_on_disk(&repository_mocap().join("dribble")),
        "each clip and its mirror image"
    );
    // A user's directory replaces it, by flag or by environment, named without its path.
    let dir = scratch("user-mocap");
    std::fs::create_dir_all(dir.path().join("run")).unwrap();
    for name in ["16_36.bvh", "16_45.bvh"] {
        std::fs::copy(
            repository_mocap().join("run").join(name),
            dir.path().join("run").join(name),
        )
        .unwrap();
    }
    let by_flag = json(&format!(
        "motion-graph --behaviour run --json --mocap {}",
        dir.path().display()
    ));
    let source = by_flag["motion_source"].as_str().unwrap();
    assert!(
        source.starts_with("user capture: 2 clips and their mirror images, fingerprint "),
        "{source}"
    );
    assert!(!source.contains(&*dir.path().to_string_lossy()), "{source}");
    assert_eq!(
        by_flag["clips"],
        serde_json::json!(["16_36", "16_36-mirror", "16_45", "16_45-mirror"])
    );
    // --no-mirror plays the clips only as captured, which is other motion: another
    // fingerprint.
    let captured = json(&format!(
        "motion-graph --behaviour run --json --no-mirror --mocap {}",
        dir.path().display()
    ));
    let plain = captured["motion_source"].as_str().unwrap();
    assert!(
        plain.starts_with("user capture: 2 clips, fingerprint "),
        "{plain}"
    );
    assert_ne!(plain, source);
    assert_eq!(captured["clips"], serde_json::json!(["16_36", "16_45"]));
    let by_env = std::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(["motion-graph", "--behaviour", "run", "--json"])
        .env("FIELDHOUSE_MOCAP_DIR", dir.path())
        .output()
        .unwrap();
    let by_env: Value = serde_json::from_slice(&by_env.stdout).unwrap();
    assert_eq!(by_env["motion_source"], by_flag["motion_source"]);
}

#[test]
fn motion_errors_name_what_is_wrong() {
    let err = failure("motion-graph --behaviour swim");
    assert!(
        err.contains("\"swim\"") && err.contains("defense, dribble, run"),
        "{err}"
    );
    // A directory that is not there names itself, what --mocap takes, and the way back
    // to the built-in capture; the OS error is said once.
    let err = failure("motion-graph --mocap /nonexistent/mocap --behaviour run");
    assert!(err.contains("/nonexistent/mocap"), "{err}");
    assert!(err.contains("one folder per behaviour"), "{err}");
    assert!(err.contains("Leave it out"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
    let err = failure("motion-graph --behaviour run --threshold -1");
    assert!(err.contains("greater than 0"), "{err}");
}

#[test]
fn a_corrupt_clip_is_reported_and_the_rest_still_load() {
    let dir = scratch("corrupt-mocap");
    let run = dir.path().join("run");
    std::fs::create_dir_all(&run).unwrap();
    for name in ["16_36.bvh", "16_45.bvh"] {
        std::fs::copy(repository_mocap().join("run").join(name), run.join(name)).unwrap();
    }
    let good = std::fs::read_to_string(repository_mocap().join("run/16_41.bvh")).unwrap();
    std::fs::write(run.join("16_41.bvh"), &good[..good.len() / 2]).unwrap();
    // A number spoilt on line 300 (a frame line) is reported at that line.
    let mut lines: Vec<&str> = good.lines().collect();
    lines[299] = "0.0 1.5e NaNish";
    std::fs::write(run.join("16_99.bvh"), lines.join("\n")).unwrap();
    let out = fieldhouse(&format!(
        "motion-graph --mocap {} --behaviour run --json",
        dir.path().display()
    ));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("16_41.bvh:") && err.contains("skipped a motion clip"),
        "{err}"
    );
    assert!(
        err.contains("16_99.bvh:300: expected 96 channel values"),
        "{err}"
    );
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    // Each clip that loads is played as captured and mirrored.
    assert_eq!(
        doc["clips"],
        serde_json::json!(["16_36", "16_36-mirror", "16_45", "16_45-mirror"])
    );
}

fn costmap(extra: &str, cache: &Path) -> Value {
    json(&format!(
        "costmap --behaviour run --size 12 --depth 120 --cache-dir {} --json {extra}",
        cache.display()
    ))
}

#[test]
fn a_cost_map_is_a_grid_of_frames_in_the_agents_frame() {
    let cache = scratch("costmap-grid");
    let doc = costmap("--method search --obstacle 2,-1,3,1", cache.path());
    let (cell, size) = (
        doc["cell_m"].as_f64().unwrap(),
        doc["size_m"].as_f64().unwrap(),
    );
    let rows = doc["costs"].as_array().unwrap();
    let n = (size / cell).round() as usize;
    assert_eq!(rows.len(), n);
    assert!(rows.iter().all(|r| r.as_array().unwrap().len() == n));
    assert_eq!(doc["origin"], serde_json::json!([-size / 2.0, -size / 2.0]));
    assert_eq!(doc["method"], "search");
    let top = doc["top_speed_m_s"].as_f64().unwrap();
    assert!(top > 2.0 && top < 9.0, "{top}");
    // costs[i][j] is the cell whose centre is (origin.x + (j + ½)·cell, origin.z + (i + ½)·cell).
    let at = |x: f64, z: f64| {
        let (j, i) = (
            ((x + size / 2.0) / cell) as usize,
            ((z + size / 2.0) / cell) as usize,
        );
        rows[i][j].clone()
    };
    assert_eq!(at(0.1, 0.1), 0, "the agent's own cell costs nothing");
    assert!(
        at(2.6, 0.2).is_null(),
        "a cell inside an obstacle is unreachable"
    );
    let ahead = at(1.6, 0.2)
        .as_u64()
        .expect("reachable ahead, before the obstacle");
    // Nothing is faster than a straight line at the top speed.
    assert!(ahead as f64 >= (1.5 / top * 30.0).floor(), "{ahead}");
}

#[test]
fn cost_maps_are_cached_and_a_corrupt_cache_is_rebuilt() {
    let cache = scratch("costmap-cache");
    let first = costmap("--method mc --iterations 3000", cache.path());
    assert_eq!(first["from_cache"], false);
    let again = costmap("--method mc --iterations 3000", cache.path());
    assert_eq!(again["from_cache"], true);
    assert_eq!(again["costs"], first["costs"]);
    // Other parameters, another map.
    assert_eq!(
        costmap("--method mc --iterations 3001", cache.path())["from_cache"],
        false
    );
    for entry in std::fs::read_dir(cache.path()).unwrap() {
        std::fs::write(entry.unwrap().path(), b"{\"costs\": [[1, 2").unwrap();
    }
    let rebuilt = costmap("--method mc --iterations 3000", cache.path());
    assert_eq!(rebuilt["from_cache"], false);
    assert_eq!(rebuilt["costs"], first["costs"]);
}

#[test]
fn the_heat_map_is_a_png_of_the_grid() {
    let dir = scratch("costmap-png");
    let file = dir.path().join("run.png");
    let out = fieldhouse(&format!(
        "costmap --behaviour run --method grassfire --size 10 --cell 0.5 --no-cache --png {}",
        file.display()
    ));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let decoder = png::Decoder::new(std::fs::File::open(&file).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgb).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let (width, height) = (info.width as usize, info.height as usize);
    let luma = |x: usize, y: usize| {
        let k = (y * width + x) * 3;
        (u32::from(rgb[k]) + u32::from(rgb[k + 1]) + u32::from(rgb[k + 2])) / 3
    };
    let white = |x: usize, y: usize| rgb[(y * width + x) * 3..][..3] == [255, 255, 255];
    // The map, 20 cells of 12 px, sits under a title band: its first row not white.
    let top = (0..height).find(|&y| !white(120, y)).unwrap();
    let top = (top..height)
        .find(|&y| (0..240).all(|x| !white(x, y)))
        .unwrap();
    assert!(top >= 20, "no room for a title above the map (top {top})");
    let ink = |rows: std::ops::Range<usize>| {
        rows.flat_map(|y| (0..width).map(move |x| (x, y)))
            .filter(|&(x, y)| luma(x, y) < 80)
            .count()
    };
    assert!(ink(0..top) > 100, "no title above the map");
    // Below it, a colour scale: a row running from black to white, never darker to the
    // right, over at least 150 px.
    let scale = (top + 240..height).any(|y| {
        let (mut run, mut from) = (0, 0);
        (1..width).any(|x| {
            if luma(x, y) >= luma(x - 1, y) && !white(x, y) {
                if run == 0 {
                    from = luma(x - 1, y);
                }
                run += 1;
            } else {
                run = 0;
            }
            run >= 150 && from < 20 && luma(x, y) > 230
        })
    });
    assert!(scale, "no colour scale under the map");
    assert!(ink(top + 240..height) > 200, "no words under the map");
}

#[test]
fn costmap_arguments_are_checked() {
    let base = "costmap --behaviour run --no-cache";
    let err = failure(&format!("{base} --obstacle 1,2,3"));
    assert!(err.contains("X0,Z0,X1,Z1"), "{err}");
    let err = failure(&format!("{base} --obstacle 1,2,1,5"));
    assert!(err.contains("no area"), "{err}");
    let err = failure(&format!("{base} --method astar"));
    assert!(
        err.contains("expected one of mc, search, grassfire"),
        "{err}"
    );
    let err = failure(&format!("{base} --start 99999"));
    assert!(err.contains("the graph has nodes 0 to"), "{err}");
    let err = failure(&format!("{base} --start 16_36:x"));
    assert!(err.contains("CLIP:FRAME"), "{err}");
    let err = failure(&format!("{base} --start 99_99:3"));
    assert!(err.contains("no clip 99_99"), "{err}");
    let err = failure(&format!("{base} --cell 0"));
    assert!(err.contains("greater than 0"), "{err}");
}

#[test]
fn an_interrupted_build_leaves_no_cache_file() {
    let cache = scratch("costmap-interrupt");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(
            format!(
                "costmap --behaviour run --method mc --iterations 50000000 --cache-dir {}",
                cache.path().display()
            )
            .split_whitespace(),
        )
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Let the build get well into its work (50 million iterations take far longer) so
    // the kill lands in the middle of it.
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the build finished before it could be interrupted"
    );
    child.kill().unwrap();
    child.wait().unwrap();
    let left: Vec<_> = std::fs::read_dir(cache.path())
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    assert!(left.is_empty(), "an interrupted build left {left:?}");
    // The next run builds from scratch and caches a complete map.
    let doc = costmap("--method mc --iterations 2000", cache.path());
    assert_eq!(doc["from_cache"], false);
    assert_eq!(
        costmap("--method mc --iterations 2000", cache.path())["from_cache"],
        true
    );
}

/// `fieldhouse capability --json`, the interface others build on: per behaviour and start
/// state the frames to the nine squares and grassfire's, per clip the coverage; checked
/// against what must hold whatever the data (grassfire grows with distance, every clip
/// keeps half its frames, `standing` is the slowest state) rather than against numbers.
#[test]
fn the_capability_report_covers_every_behaviour_state_and_clip() {
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capability-cache");
    let doc = json(&format!(
        "capability --json --cache-dir {}",
        cache.display()
    ));
    let keys = [
        "ahead_1m",
        "ahead_3m",
        "ahead_5m",
        "left_1m",
        "left_3m",
        "right_1m",
        "right_3m",
        "behind_3m",
        "behind_5m",
    ];
    let behaviours = doc["behaviours"].as_array().unwrap();
    let names: Vec<&str> = behaviours
        .iter()
        .map(|b| b["behaviour"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["dribble", "run", "defense"]);
    for b in behaviours {
        for c in b["clips"].as_array().unwrap() {
            let (frames, kept) = (c["frames"].as_u64().unwrap(), c["kept"].as_u64().unwrap());
            assert!(2 * kept >= frames, "{c}");
        }
        let states = b["states"].as_array().unwrap();
        assert_eq!(states[0]["name"], "standing");
        let speed = |s: &Value| s["root_speed_m_s"].as_f64().unwrap();
        assert!(states.iter().all(|s| speed(&states[0]) <= speed(s)));
        for s in states {
            for k in keys {
                let f = &s["frames_to"][k];
                assert!(f.is_null() || f.is_u64(), "{k}: {f}");
                assert!(s["grassfire"][k].is_u64(), "{k}");
            }
            let g = |k: &str| s["grassfire"][k].as_u64().unwrap();
            assert!(g("ahead_1m") < g("ahead_3m") && g("ahead_3m") < g("ahead_5m"));
            assert!(g("left_1m") < g("left_3m") && g("right_1m") < g("right_3m"));
            assert!(g("behind_3m") < g("behind_5m"));
        }
    }
    // The two jump shots (and their mirror images) are cut from the dribbling, with the
    // time a shot takes.
    let jumps = behaviours[0]["jumps_cut"].as_array().unwrap();
    assert_eq!(jumps.len(), 4, "{jumps:?}");
    // Every target against people: measured from a stance, with the human figure and its
    // source, met exactly when the frames are within the target.
    let fps = doc["fps"].as_f64().unwrap();
    let targets = doc["targets"].as_array().unwrap();
    assert!(targets.len() >= 9, "{targets:?}");
    for t in targets {
        assert!(!t["source"].as_str().unwrap().is_empty() && t["people"].is_string());
        let within = t["frames"]
            .as_u64()
            .is_some_and(|f| f as f64 / fps <= t["target_s"].as_f64().unwrap() + 1e-9);
        let stance =
            t["state_speed_m_s"].as_f64().unwrap() < doc["stance_below_m_s"].as_f64().unwrap();
        assert_eq!(t["met"].as_bool().unwrap(), within && stance, "{t}");
        if !within && t["frames"].is_u64() {
            assert!(!t["walk"].as_array().unwrap().is_empty(), "{t}");
        }
    }
}

#[test]
fn a_cost_map_starts_from_the_state_asked_for() {
    let start = |s: &str| {
        json(&format!(
            "costmap --behaviour run --depth 30 --size 6 --no-cache --json --start {s}"
        ))["start"]
            .clone()
    };
    let (standing, moving) = (start("standing"), start("moving"));
    assert!(
        standing["root_speed_m_s"].as_f64().unwrap() < moving["root_speed_m_s"].as_f64().unwrap()
    );
    assert_eq!(standing["given"], "standing");
    let node = moving["node"].as_u64().unwrap();
    assert_eq!(start(&node.to_string())["node"], node);
    let clip_frame = format!("{}:{}", moving["clip"].as_str().unwrap(), moving["frame"]);
    assert_eq!(start(&clip_frame)["node"], node);
    let err = failure("costmap --behaviour run --start sitting");
    assert!(err.contains("default, standing, moving"), "{err}");
}
