//! `fieldhouse basketball-decide` and `basketball-eval` as a user runs them, on the CMU
//! motion capture. Maps are cached in the test target directory, keyed by their inputs.

use crate::common;

use common::{assert_reads_well, failure, json, success};
use serde_json::Value;

fn source() -> String {
    format!(
        "--cache-dir {}",
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join("basketball-cache")
            .display()
    )
}

fn decide(shooter: &str, defender: &str) -> Value {
    json(&format!(
        "basketball-decide --shooter {shooter} --defender {defender} --json {}",
        source()
    ))
}

fn num(v: &Value) -> f64 {
    v.as_f64().expect("a number")
}

#[test]
fn every_chosen_square_satisfies_the_rule_and_none_better_does() {
    let doc = decide("9,2,180", "4,0,0");
    let chosen = &doc["chosen"];
    let (t_s, epsilon) = (num(&chosen["t_s"]), num(&chosen["epsilon"]));
    assert!(num(&chosen["c_o"]) > num(&chosen["c_d"]) + t_s + epsilon);
    let candidates = doc["candidates"].as_array().unwrap();
    assert!(
        candidates.len() > 100,
        "the shooter reaches much of the court"
    );
    let mut qualifying = 0;
    for c in candidates {
        let (c_o, c_d) = (num(&c["c_o"]), num(&c["c_d"]));
        assert!(c_o >= 0.0 && c_d >= 0.0);
        if c_o > c_d + t_s + epsilon {
            qualifying += 1;
            assert!(
                num(&c["success"]) <= num(&chosen["success"]),
                "{c} beats {chosen}"
            );
        }
    }
    assert_eq!(qualifying, doc["qualifying"].as_u64().unwrap());
    // The chosen square is one of the candidates, with the same times.
    assert!(candidates
        .iter()
        .any(|c| c["cell"] == chosen["cell"] && c["c_o"] == chosen["c_o"]));
}

#[test]
fn a_defender_on_the_chosen_square_sends_the_shooter_elsewhere_or_to_the_plan() {
    let first = decide("9,2,180", "12,-6,90");
    let cell = first["chosen"]["cell"].as_array().unwrap().clone();
    let (x, z) = (num(&cell[0]), num(&cell[1]));
    let second = decide("9,2,180", &format!("{x},{z},0"));
    assert_ne!(second["chosen"]["cell"], first["chosen"]["cell"]);
}

#[test]
fn decide_shows_the_defenders_own_times_beside_the_models() {
    let doc = |model: &str| {
        json(&format!(
            "basketball-decide --shooter 10,3,200 --defender 5,-1,20 --shot-model {model} --defense defense --json {}",
            source()
        ))
    };
    // Modelled with its own map, the model is the truth: the same times, no square in
    // dispute.
    let same = doc("own");
    assert_eq!(same["shot_model"], "own");
    let candidates = same["candidates"].as_array().unwrap();
    let own = same["c_o_own_s"].as_array().unwrap();
    assert_eq!(own.len(), candidates.len());
    for (c, o) in candidates.iter().zip(own) {
        assert_eq!(num(&c["c_o"]), num(o));
    }
    assert_eq!(same["model_safe_but_reached"], 0);
    assert_eq!(same["model_unsafe_but_safe"], 0);
    // Modelled with the shooter's run map (the paper), they differ somewhere, and the
    // counts are what the two lists of times say.
    let paper = doc("paper");
    assert_eq!(paper["shot_model"], "paper");
    let rule = |c: &Value, c_o: f64| c_o > num(&c["c_d"]) + 0.4 + 0.2;
    let (mut safe_but_reached, mut unsafe_but_safe) = (0, 0);
    for (c, o) in paper["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .zip(paper["c_o_own_s"].as_array().unwrap())
    {
        let (model, truth) = (rule(c, num(&c["c_o"])), rule(c, num(o)));
        safe_but_reached += u64::from(model && !truth);
        unsafe_but_safe += u64::from(!model && truth);
    }
    assert_eq!(paper["model_safe_but_reached"], safe_but_reached);
    assert_eq!(paper["model_unsafe_but_safe"], unsafe_but_safe);
    assert!(
        safe_but_reached + unsafe_but_safe > 0,
        "the run map is not the footwork's"
    );
}

#[test]
fn bad_decisions_are_refused_with_the_reason() {
    let err = failure("basketball-decide --shooter 9,2 --defender 4,0,0");
    assert!(err.contains("X,Z,HEADING_DEG"), "{err}");
    let err = failure(&format!(
        "basketball-decide --shooter 20,0,0 --defender 4,0,0 {}",
        source()
    ));
    assert!(err.contains("off the court"), "{err}");
    let err = failure("basketball-decide --shooter 9,2,180 --defender 4,0,0 --epsilon -1");
    assert!(err.contains("must not be negative"), "{err}");
    let err = failure("basketball-decide --shooter 9,2,180");
    assert!(err.contains("--defender"), "{err}");
    let err = failure("basketball-eval --offense lot --possessions 5");
    assert!(err.contains("simple") && err.contains("costmap"), "{err}");
}

fn eval(extra: &str) -> Value {
    let mut doc = json(&format!("basketball-eval --json {extra} {}", source()));
    doc.as_object_mut().unwrap().remove("elapsed_s");
    doc
}

#[test]
fn an_evaluation_accounts_for_every_possession_and_repeats_exactly() {
    let doc = eval("--offense costmap --possessions 40 --seed 3");
    for key in [
        "points_per_possession",
        "possessions",
        "shots",
        "blocked",
        "stolen",
        "passes",
    ] {
        assert!(doc.get(key).is_some(), "missing {key}: {doc}");
    }
    let count = |k: &str| doc[k].as_u64().unwrap();
    assert_eq!(count("possessions"), 40);
    // Each possession ends in exactly one way: a shot (made, missed or blocked), a
    // steal or interception, or the shot clock.
    assert_eq!(
        count("shots") + count("stolen") + count("shot_clock_violations"),
        40
    );
    assert!(count("made") + count("blocked") <= count("shots"));
    assert!((num(&doc["points_per_possession"]) - count("points") as f64 / 40.0).abs() < 1e-12);
    assert_eq!(eval("--offense costmap --possessions 40 --seed 3"), doc);
    assert_ne!(eval("--offense costmap --possessions 40 --seed 4"), doc);
}

#[test]
fn both_offenses_are_compared_on_the_same_possessions() {
    let doc = eval("--possessions 30 --seed 2");
    let reports = doc["reports"].as_array().unwrap();
    assert_eq!(reports[0]["offense"], "simple");
    assert_eq!(reports[1]["offense"], "costmap");
    let diff =
        num(&reports[1]["points_per_possession"]) - num(&reports[0]["points_per_possession"]);
    assert!((num(&doc["comparison"]["difference"]) - diff).abs() < 1e-12);
    // The paired statistics, computed again from the per-possession outcomes the JSON
    // lists: differences, their sample variance by the textbook sum of squares, and
    // the normal 95 % interval.
    let points = |r: &serde_json::Value| -> Vec<f64> {
        r["by_possession"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| num(&p["points"]))
            .collect()
    };
    let (a, b) = (points(&reports[1]), points(&reports[0]));
    assert_eq!((a.len(), b.len()), (30, 30));
    let d: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x - y).collect();
    let n = d.len() as f64;
    let sum: f64 = d.iter().sum();
    let sum_sq: f64 = d.iter().map(|x| x * x).sum();
    let se = ((sum_sq - sum * sum / n) / (n - 1.0) / n).sqrt();
    let c = &doc["comparison"];
    assert!((num(&c["difference"]) - sum / n).abs() < 1e-12);
    assert!((num(&c["standard_error"]) - se).abs() < 1e-9);
    assert!((num(&c["ci95"][0]) - (sum / n - 1.96 * se)).abs() < 1e-3);
    assert!((num(&c["z"]) - sum / n / se).abs() < 1e-6);
    let (text, _) = success(&format!(
        "basketball-eval --possessions 30 --seed 2 {}",
        source()
    ));
    assert!(
        text.contains("paired over the same 30 possessions"),
        "{text}"
    );
    assert_reads_well(&text);
}

#[test]
fn the_defender_model_is_named_and_bad_ones_are_refused() {
    let doc = eval("--possessions 20 --seed 2 --shot-model isotropic --pass-model none --reaction-s 0.5 --isotropic-speed 6");
    assert_eq!(doc["shot_model"]["kind"], "isotropic");
    assert_eq!(num(&doc["shot_model"]["reaction_s"]), 0.5);
    assert_eq!(num(&doc["shot_model"]["speed_m_s"]), 6.0);
    assert_eq!(doc["pass_model"]["kind"], "none");
    let err = common::failure(&format!(
        "basketball-eval --possessions 20 --shot-model psychic {}",
        source()
    ));
    assert!(
        err.contains("psychic") && err.contains("isotropic"),
        "{err}"
    );
    // basketball-decide names its models as basketball-eval does, with the same default
    // (the defender's own maps, as live matches play), and refuses the fitted ones
    // naming the command that has them.
    let decided = json(&format!(
        "basketball-decide --shooter 10,3,200 --defender 5,-1,20 --json {}",
        source()
    ));
    assert_eq!(decided["shot_model"], "own");
    let err = common::failure(&format!(
        "basketball-decide --shooter 10,3,200 --defender 5,-1,20 --shot-model isotropic {}",
        source()
    ));
    assert!(err.contains("basketball-eval"), "{err}");
}

#[test]
fn one_possession_is_counted_in_the_singular() {
    let (text, _) = success(&format!(
        "basketball-eval --offense simple --possessions 1 --seed 2 {}",
        source()
    ));
    assert!(text.starts_with("1 possession on seed 2,"), "{text}");
    assert_reads_well(&text);
    let (text, _) = success(&format!(
        "basketball-decide --shooter 10,3,200 --defender 5,-1,20 {}",
        source()
    ));
    assert_reads_well(&text);
}

#[test]
fn a_first_start_finds_the_shipped_graphs_and_maps_and_builds_nothing() {
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("shipped-start-cache");
    let _ = std::fs::remove_dir_all(&cache);
    let (_, log) = success(&format!(
        "basketball-eval --offense simple --possessions 1 --cache-dir {}",
        cache.display()
    ));
    for behaviour in ["run", "dribble", "defense"] {
        assert!(
            log.contains(&format!("{behaviour}: cost maps shipped with fieldhouse")),
            "{log}"
        );
    }
    assert!(!log.contains("searching"), "{log}");
    assert!(!log.contains("motion graph of"), "{log}");
    // Nothing was built, so nothing was cached.
    assert!(!cache.exists(), "{}", cache.display());
}

#[test]
fn a_first_start_of_other_motion_shows_each_stage_and_the_next_start_reads_the_cache() {
    // The capture unmirrored is other motion than what fieldhouse ships graphs and maps
    // of (its fingerprint differs), so they are built, then cached.
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("first-start-cache");
    let _ = std::fs::remove_dir_all(&cache);
    let stages = || {
        success(&format!(
            "basketball-eval --offense simple --possessions 1 --no-mirror --cache-dir {}",
            cache.display()
        ))
        .1
    };
    let first = stages();
    for behaviour in ["run", "dribble", "defense"] {
        for stage in [
            "motion graph of",
            "searching its cost maps",
            "cost maps built",
        ] {
            assert!(
                first.contains(&format!("{behaviour}: {stage}")),
                "no '{behaviour}: {stage}' in:\n{first}"
            );
        }
    }
    let second = stages();
    // The graphs are cached beside their maps: nothing is built again.
    assert!(!second.contains("searching"), "{second}");
    assert!(!second.contains("motion graph of"), "{second}");
    for behaviour in ["run", "dribble", "defense"] {
        assert!(
            second.contains(&format!("{behaviour}: cost maps read from the cache")),
            "{second}"
        );
    }
}
