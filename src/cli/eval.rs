//! `fieldhouse basketball-eval`: the paper's possession experiment, with the cost-map
//! offense's model of the defender chosen for the shot and the pass separately.

use super::args::{non_negative, parse_str, positive, probability};
use super::basketball::CapabilityArgs;
use super::model_spec::ModelSpec;
use clap::Args;
use fieldhouse::basketball::parametric::{self, FitQuality, Isotropic};
use fieldhouse::basketball::{
    compare, evaluate, BeyondHorizon, Brain, Capabilities, DefenderAim, DefenderModel,
    DefenderMotion, EvalReport, GameParams,
};
use fieldhouse::words::plural;
use serde_json::{json, Value};
use std::io::Write;
use std::str::FromStr;
use std::sync::Arc;
use std::time::Instant;

#[derive(Args, Debug)]
#[command(
    after_help = "Possession k starts from the same random positions whatever the offense or model \
        (seeded by --seed and k), with the same random draws: the ball handler at x 8–12 m, z ±5 m; \
        the teammate 5–10 m out on the other side; the defender 3 m from the ball handler toward \
        the basket. Runs with the same seed and possessions pair possession by possession (--json \
        lists each one's points).\n\
        Models of the defender: own (the defender's own maps: exact, an upper bound), paper (the \
        shooter's run maps, as in the paper), maps:BEHAVIOUR (another behaviour's or subject's \
        maps, e.g. maps:run-127), kinematic (reaction, turn rate, acceleration and a top speed \
        forward, sideways and backward, fitted to the --fit-to maps by least squares), isotropic \
        (reaction + distance / speed, fitted the same way unless --isotropic-speed sets it), none.\n\
        With several seeds or models, every combination (an arm) is played on every seed, the \
        capabilities and fits built once; --json then gives {\"seeds\", \"simple\", \"arms\"}.\n\
        Example: fieldhouse basketball-eval --offense costmap --shot-model own,kinematic --seed 7001,7002"
)]
pub(super) struct EvalArgs {
    /// simple, costmap, or both (the same possessions for each, with the same random
    /// draws, compared possession by possession).
    #[arg(long, default_value = "both")]
    offense: String,
    /// How the defender moves: defense (footwork), run, or another behaviour of the
    /// motion (a folder of --mocap, or of the embedded capture, such as run-127).
    #[arg(long, default_value = "defense")]
    defense: String,
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    possessions: u64,
    /// The seed, or several separated by commas: each is a run of its own, reported
    /// apart (the capabilities and fits are built once for all).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    seed: Vec<u64>,
    /// The defender's reach, m.
    #[arg(long, value_name = "M", default_value_t = GameParams::default().defender.reach_m, value_parser = positive)]
    reach: f64,
    /// The chance the defender blocks a shot it reaches before the ball is away.
    #[arg(long, value_name = "P", default_value_t = GameParams::default().defender.block_success, value_parser = probability)]
    block_success: f64,
    /// Where the defender heads: ball (where the ball is, as the paper's defender does)
    /// or goal (where the ball handler is dribbling to: a defender that reads the play).
    #[arg(long, default_value = "ball", value_parser = parse_str::<DefenderAim>)]
    defender_aim: DefenderAim,
    /// The chance one steal attempt on a dribbler (or a pass in flight) succeeds.
    #[arg(long, value_name = "P", default_value_t = GameParams::default().defender.steal_success, value_parser = probability)]
    steal_success: f64,
    /// How the cost-map offense models the defender when it picks where to shoot (see
    /// below). Several, separated by commas, are each played (with every --pass-model).
    #[arg(long, value_delimiter = ',', default_value = "own", value_parser = ModelSpec::from_str)]
    shot_model: Vec<ModelSpec>,
    /// How it models the defender when it decides whether it is pressed and passes:
    /// pressed when the modelled defender reaches the ball within 1 s; with none, when
    /// the defender is inside the simple offense's fixed radius. Several: as --shot-model.
    #[arg(long, value_delimiter = ',', default_value = "own", value_parser = ModelSpec::from_str)]
    pass_model: Vec<ModelSpec>,
    /// The maps the kinematic and isotropic models are fitted to: own (the defender's) or
    /// a behaviour's (run, defense, run-127, ...).
    #[arg(long, default_value = "own")]
    fit_to: String,
    /// A hand-set isotropic model's speed, m/s (with --reaction-s), instead of a fitted one.
    #[arg(long, value_name = "M/S", value_parser = positive)]
    isotropic_speed: Option<f64>,
    /// A hand-set isotropic model's reaction time, s (default 0; needs --isotropic-speed).
    #[arg(long, value_name = "S", value_parser = non_negative, requires = "isotropic_speed")]
    reaction_s: Option<f64>,
    /// What a square the defender's maps do not reach counts as: horizon (C_o is the
    /// map's horizon: the defender needs at least that) or unsafe (never shoot there).
    #[arg(long, default_value = "horizon", value_parser = parse_str::<BeyondHorizon>)]
    beyond_horizon: BeyondHorizon,
    /// The simple offense shoots from this close to the basket, m.
    #[arg(long, value_name = "M", default_value_t = GameParams::default().simple.shoot_range_m, value_parser = positive)]
    simple_range: f64,
    /// Print one JSON document.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    capability: CapabilityArgs,
}

/// A fitted model and how well it fits the maps.
struct Fit<T> {
    model: T,
    quality: FitQuality,
}

/// One combination of models played: what the cost-map offense models the defender
/// with to shoot and to pass, and its report on each seed.
struct Arm {
    shot: DefenderModel,
    pass: DefenderModel,
    runs: Vec<EvalReport>,
}

pub(super) fn run(args: EvalArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let brains: Vec<Brain> = match args.offense.as_str() {
        "both" => vec![Brain::Simple, Brain::Costmap],
        one => vec![parse_str::<Brain>(one).map_err(|e| anyhow::anyhow!("{e}; or both"))?],
    };
    let library = args.capability.library()?;
    let motion = DefenderMotion::any(&args.defense);
    let specs: Vec<&ModelSpec> = args.shot_model.iter().chain(&args.pass_model).collect();
    // Every behaviour named that is not built in becomes a capture of its own.
    let mut captures = vec![motion.name().to_string()];
    for spec in &specs {
        if let ModelSpec::Maps(b) = spec {
            captures.push(b.clone());
        }
    }
    if args.fit_to != "own" {
        captures.push(args.fit_to.clone());
    }
    for name in &captures {
        anyhow::ensure!(
            library.behaviours().contains(&name.as_str()),
            "no behaviour \"{name}\" in {}; it has: {}",
            library.source,
            library.behaviours().join(", ")
        );
    }
    let caps = Arc::new(args.capability.build_with(&library, &captures)?);
    let fitted_to = if args.fit_to == "own" {
        caps.defender(motion)
    } else {
        caps.by_behaviour(&args.fit_to)
            .expect("built with the captures above")
    };
    let wants = |m: &ModelSpec| specs.contains(&m);
    let samples = (wants(&ModelSpec::Kinematic) || wants(&ModelSpec::Isotropic))
        .then(|| parametric::samples(fitted_to));
    let samples = samples.as_deref().unwrap_or(&[]);
    let kinematic = wants(&ModelSpec::Kinematic).then(|| {
        let (model, quality) = parametric::fit_kinematic(samples);
        Fit { model, quality }
    });
    let isotropic = wants(&ModelSpec::Isotropic).then(|| match args.isotropic_speed {
        Some(speed_m_s) => {
            let model = Isotropic {
                reaction_s: args.reaction_s.unwrap_or(0.0),
                speed_m_s,
            };
            let quality = parametric::quality(samples, |s| model.seconds(s.at));
            Fit { model, quality }
        }
        None => {
            let (model, quality) = parametric::fit_isotropic(samples);
            Fit { model, quality }
        }
    });
    let resolve = |spec: &ModelSpec| match spec {
        ModelSpec::Own => DefenderModel::Own,
        ModelSpec::Maps(b) => DefenderModel::Maps {
            behaviour: DefenderMotion::any(b),
        },
        ModelSpec::Kinematic => {
            DefenderModel::Kinematic(kinematic.as_ref().expect("fitted above").model)
        }
        ModelSpec::Isotropic => {
            DefenderModel::Isotropic(isotropic.as_ref().expect("fitted above").model)
        }
        ModelSpec::None => DefenderModel::None,
    };
    let mut params = GameParams::default();
    params.defender.motion = motion;
    params.defender.reach_m = args.reach;
    params.defender.block_success = args.block_success;
    params.defender.aim = args.defender_aim;
    params.defender.steal_success = args.steal_success;
    params.simple.shoot_range_m = args.simple_range;
    params.decision.beyond_horizon = args.beyond_horizon;
    let mut arms: Vec<Arm> = Vec::new();
    if brains.contains(&Brain::Costmap) {
        for shot in &args.shot_model {
            for pass in &args.pass_model {
                arms.push(Arm {
                    shot: resolve(shot),
                    pass: resolve(pass),
                    runs: Vec::new(),
                });
            }
        }
    }
    let started = Instant::now();
    // The simple offense knows no model: one run per seed serves every arm.
    let simple: Vec<EvalReport> = if brains.contains(&Brain::Simple) {
        let games: Vec<GameParams> = args
            .seed
            .iter()
            .map(|&seed| GameParams {
                seed,
                offense: Brain::Simple,
                ..params
            })
            .collect();
        play_all(&caps, &games, args.possessions)
    } else {
        Vec::new()
    };
    let games: Vec<GameParams> = arms
        .iter()
        .flat_map(|arm| {
            args.seed.iter().map(move |&seed| GameParams {
                seed,
                offense: Brain::Costmap,
                shot_model: arm.shot,
                pass_model: arm.pass,
                ..params
            })
        })
        .collect();
    let mut reports = play_all(&caps, &games, args.possessions).into_iter();
    for arm in &mut arms {
        arm.runs = reports.by_ref().take(args.seed.len()).collect();
    }
    let elapsed_s = started.elapsed().as_secs_f64();

    let fits = json!({
        "fitted_to": fitted_to.behaviour,
        "kinematic": kinematic.as_ref().map(|f| json!({"model": f.model, "fit": f.quality})),
        "isotropic": isotropic.as_ref().map(|f| json!({"model": f.model, "fit": f.quality, "hand_set": args.isotropic_speed.is_some()})),
    });
    let setting = json!({
        "possessions": args.possessions,
        "block_success": args.block_success,
        "defender_aim": args.defender_aim.name(),
        "steal_success": args.steal_success,
        "simple_range_m": args.simple_range,
        "defense": motion.name(),
        "beyond_horizon": args.beyond_horizon.name(),
        "fits": fits,
        "elapsed_s": elapsed_s,
        "motion_source": caps.source.to_string(),
    });
    if args.json {
        let doc = match (&arms[..], &args.seed[..]) {
            // One arm on one seed: the two offenses side by side, as a single comparison.
            (arms, [seed]) if arms.len() <= 1 => {
                let reports: Vec<&EvalReport> = simple
                    .iter()
                    .chain(arms.iter().flat_map(|a| &a.runs))
                    .collect();
                let mut doc = match &reports[..] {
                    [one] => serde_json::to_value(one)?,
                    [simple, costmap] => json!({
                        "reports": [simple, costmap],
                        "comparison": compare(costmap, simple),
                    }),
                    _ => unreachable!("one or two offenses"),
                };
                doc["seed"] = json!(seed);
                if let Some(arm) = arms.first() {
                    doc["shot_model"] = json!(arm.shot);
                    doc["pass_model"] = json!(arm.pass);
                }
                merge(&mut doc, &setting);
                doc
            }
            _ => {
                let mut doc = json!({
                    "seeds": args.seed,
                    "simple": simple,
                    "arms": arms.iter().map(|a| json!({
                        "shot_model": a.shot,
                        "pass_model": a.pass,
                        "runs": a.runs,
                    })).collect::<Vec<_>>(),
                });
                merge(&mut doc, &setting);
                doc
            }
        };
        writeln!(out, "{doc}")?;
        return Ok(());
    }
    print_text(out, &args, &caps, motion, &setting, &simple, &arms)
}

/// Copies `from`'s fields into the object `into`.
fn merge(into: &mut Value, from: &Value) {
    if let (Some(into), Some(from)) = (into.as_object_mut(), from.as_object()) {
        for (k, v) in from {
            into.insert(k.clone(), v.clone());
        }
    }
}

/// Plays every game of `games` for `possessions`, two at a time (the machine's cores),
/// in order.
fn play_all(caps: &Arc<Capabilities>, games: &[GameParams], possessions: u64) -> Vec<EvalReport> {
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<(usize, EvalReport)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers.min(games.len()))
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&game) = games.get(i) else { break };
                        mine.push((i, evaluate(caps.clone(), game, possessions)));
                    }
                    mine
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("an evaluation panicked"))
            .collect()
    });
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, r)| r).collect()
}

fn print_text(
    out: &mut impl Write,
    args: &EvalArgs,
    caps: &Capabilities,
    motion: DefenderMotion,
    setting: &Value,
    simple: &[EvalReport],
    arms: &[Arm],
) -> anyhow::Result<()> {
    let seeds: Vec<String> = args.seed.iter().map(u64::to_string).collect();
    writeln!(
        out,
        "{} on {} {}, defender moving with {} (motion: {}); beyond a map's horizon counts as {}; the simple offense shoots from {:.1} m",
        plural(args.possessions, "possession"),
        if seeds.len() == 1 { "seed" } else { "each of seeds" },
        seeds.join(", "),
        motion.name(),
        caps.source,
        args.beyond_horizon.name(),
        args.simple_range
    )?;
    let fits = &setting["fits"];
    for (kind, fit) in [
        ("kinematic", &fits["kinematic"]),
        ("isotropic", &fits["isotropic"]),
    ] {
        if fit.is_null() {
            continue;
        }
        let how = if fit["hand_set"].as_bool() == Some(true) {
            "hand-set, against"
        } else {
            "fitted to"
        };
        writeln!(
            out,
            "{kind} model, {how} the {} maps: {}; RMS error {:.2} s, bias {:+.2} s, R² {:.2} over {} cells",
            fits["fitted_to"].as_str().unwrap_or(""),
            fit["model"],
            fit["fit"]["rms_s"].as_f64().unwrap_or(f64::NAN),
            fit["fit"]["bias_s"].as_f64().unwrap_or(f64::NAN),
            fit["fit"]["r2"].as_f64().unwrap_or(f64::NAN),
            fit["fit"]["samples"]
        )?;
    }
    writeln!(
        out,
        "{:<6} {:<8} {:<22} {:>8} {:>7} {:>6} {:>6} {:>8} {:>8} {:>9} {:>7} {:>8} {:>9}",
        "seed",
        "offense",
        "models (shot / pass)",
        "pts/poss",
        "± se",
        "shots",
        "made",
        "blocked",
        "stolen",
        "shotclock",
        "passes",
        "shot m",
        "poss s"
    )?;
    let row = |out: &mut dyn Write, seed: u64, models: &str, r: &EvalReport| {
        let n = r.possessions as f64;
        writeln!(
            out,
            "{:<6} {:<8} {:<22} {:>8.3} {:>7.3} {:>5.0}% {:>5.0}% {:>7.1}% {:>7.1}% {:>8.1}% {:>7.2} {:>8.2} {:>9.2}",
            seed,
            r.offense,
            models,
            r.points_per_possession,
            r.standard_error,
            100.0 * r.shots as f64 / n,
            100.0 * r.made as f64 / r.shots.max(1) as f64,
            100.0 * r.blocked as f64 / n,
            100.0 * r.stolen as f64 / n,
            100.0 * r.shot_clock_violations as f64 / n,
            r.passes as f64 / n,
            r.mean_shot_distance_m,
            r.mean_possession_s
        )
    };
    for (k, &seed) in args.seed.iter().enumerate() {
        if let Some(r) = simple.get(k) {
            row(out, seed, "–", r)?;
        }
        for arm in arms {
            let models = format!("{} / {}", arm.shot.name(), arm.pass.name());
            row(out, seed, &models, &arm.runs[k])?;
            if let Some(s) = simple.get(k) {
                let c = compare(&arm.runs[k], s);
                writeln!(
                    out,
                    "       costmap − simple, paired over the same {} possessions: {:+.3} ± {:.3} points per possession (95 % CI {:+.3} to {:+.3}), z = {:.2}, two-sided p = {:.2e}",
                    c.possessions, c.difference, c.standard_error, c.ci95[0], c.ci95[1], c.z, c.p_two_sided
                )?;
            }
        }
    }
    writeln!(
        out,
        "({:.2} s)",
        setting["elapsed_s"].as_f64().unwrap_or(0.0)
    )?;
    Ok(())
}
