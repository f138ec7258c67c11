//! `fieldhouse basketball-decide`: one opponent-modelling decision, every square shown
//! (drawn by `picture`); and where the basketball commands get their motion and cached
//! maps.

mod picture;

use super::args::{ground_pose, non_negative, parse_str};
use super::costmap::CacheArgs;
use super::model_spec::ModelSpec;
use super::motion::MotionSourceArgs;
use anyhow::Context;
use clap::Args;
use fieldhouse::basketball::{
    Capabilities, Court, DecisionParams, DefenderMotion, GameParams, Motion, Mover, Opponent,
    ShotModel, Situation,
};
use fieldhouse::costmap::AgentPose;
use fieldhouse::words::{figure, plural};
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;
use std::time::Instant;

/// Where motion and cached maps come from.
#[derive(Args, Debug, Clone)]
pub(super) struct CapabilityArgs {
    #[command(flatten)]
    source: MotionSourceArgs,
    #[command(flatten)]
    cache: CacheArgs,
}

impl CapabilityArgs {
    pub(super) fn load(&self) -> anyhow::Result<Arc<Capabilities>> {
        let library = self.library()?;
        Ok(Arc::new(self.build(&library)?))
    }

    /// The motion library these capabilities are built from.
    pub(super) fn library(&self) -> anyhow::Result<fieldhouse::motion::MotionLibrary> {
        self.source.load()
    }

    /// The capabilities of `library`, built or read from the cache, logging each stage.
    pub(super) fn build(
        &self,
        library: &fieldhouse::motion::MotionLibrary,
    ) -> anyhow::Result<Capabilities> {
        self.build_with(library, &[])
    }

    /// [`CapabilityArgs::build`], with `captures` (other behaviours of the library, such
    /// as `run-127`) built too.
    pub(super) fn build_with(
        &self,
        library: &fieldhouse::motion::MotionLibrary,
        captures: &[String],
    ) -> anyhow::Result<Capabilities> {
        let started = Instant::now();
        let cache = self.cache.dir();
        // A line per stage: on first start the graphs and maps take seconds, and a user
        // (or a container's log) should see what is happening.
        let mut progress = |stage: fieldhouse::basketball::capability::Stage| {
            tracing::info!(
                elapsed_s = %figure(started.elapsed().as_secs_f64(), 2),
                "{stage}"
            );
        };
        let reuse = self.cache.reuse(cache.as_ref());
        let mut caps = Capabilities::build(library, reuse, &mut progress)
            .context("building the basketball behaviours (run, dribble, defense)")?;
        for name in captures {
            caps = caps
                .with_capture(library, name, reuse, &mut progress)
                .with_context(|| format!("building the behaviour {name}"))?;
        }
        tracing::info!(
            elapsed_s = %figure(started.elapsed().as_secs_f64(), 2),
            cache = %cache.map_or_else(|| "none".to_string(), |d| d.0.display().to_string()),
            "motion graphs and cost maps of run, dribble and defense ready"
        );
        Ok(caps)
    }
}

#[derive(Args, Debug)]
#[command(
    allow_negative_numbers = true,
    after_help = "The court is FIBA's half court: x from the baseline (0) to the half-court line (14 m), \
        z across it (−7.5 to 7.5 m), the basket at (1.575, 0). Headings are degrees from +x toward +z \
        (180 faces the basket from midcourt).\n\
        Example: fieldhouse basketball-decide --shooter 9,2,180 --defender 4,0,0 --json"
)]
pub(super) struct DecideArgs {
    /// The shooter's pose, X,Z,HEADING_DEG.
    #[arg(long, value_name = "X,Z,HEADING_DEG", value_parser = ground_pose, allow_hyphen_values = true)]
    shooter: AgentPose,
    /// A defender's pose, X,Z,HEADING_DEG (repeatable).
    #[arg(long, value_name = "X,Z,HEADING_DEG", value_parser = ground_pose, allow_hyphen_values = true, required = true)]
    defender: Vec<AgentPose>,
    /// ε, the margin the defender must be late by, s.
    #[arg(long, value_name = "S", default_value_t = DecisionParams::default().epsilon_s, value_parser = non_negative)]
    epsilon: f64,
    /// T_s, the time a shot takes, s.
    #[arg(long, value_name = "S", default_value_t = DecisionParams::default().shot_time_s, value_parser = non_negative)]
    shot_time: f64,
    /// How the shooter models the defender, named as basketball-eval names it: own (the
    /// defender's own maps, those of --defense: what live matches and basketball-eval use
    /// by default), paper (the shooter's own run maps, the paper's choice without prior
    /// knowledge) or maps:BEHAVIOUR (another behaviour's maps, e.g. maps:run-127). The
    /// fitted models (kinematic, isotropic) are basketball-eval's.
    #[arg(long, default_value = "own", value_parser = ModelSpec::from_str)]
    shot_model: ModelSpec,
    /// How the defender really moves (its own map): defense (footwork) or run. Its C_o
    /// is printed beside the model's, so the gap between the model and the truth shows.
    #[arg(long, default_value = "defense", value_parser = parse_str::<DefenderMotion>)]
    defense: DefenderMotion,
    /// Draw the decision: the shooter's dribbling times, the defender's times, and the
    /// squares that satisfy the rule with the chosen one outlined.
    #[arg(long, value_name = "FILE")]
    png: Option<PathBuf>,
    /// Print one JSON document.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    capability: CapabilityArgs,
}

fn on_court(court: &Court, who: &str, pose: &AgentPose) -> anyhow::Result<()> {
    anyhow::ensure!(
        court.contains(pose.position),
        "the {who} at ({}, {}) is off the court (x 0 to {} m, z −{} to {} m)",
        pose.position.x,
        pose.position.y,
        court.length_m,
        court.width_m / 2.0,
        court.width_m / 2.0
    );
    Ok(())
}

/// Defenders at `poses` as `mover`'s maps see them. Poses given on the command line
/// stand still: their maps are the standing ones.
fn standing<'a>(mover: &'a Mover, poses: &[AgentPose]) -> Vec<Opponent<'a>> {
    poses
        .iter()
        .map(|d| Opponent::Map(mover.reach(d, Motion::Still)))
        .collect()
}

pub(super) fn decide(args: DecideArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let court = Court::default();
    on_court(&court, "shooter", &args.shooter)?;
    for d in &args.defender {
        on_court(&court, "defender", d)?;
    }
    // A model of another behaviour's maps needs that behaviour built too.
    let captures: Vec<String> = match &args.shot_model {
        ModelSpec::Maps(b) if !["dribble", "run", "defense"].contains(&b.as_str()) => {
            vec![b.clone()]
        }
        _ => Vec::new(),
    };
    let library = args.capability.library()?;
    for b in &captures {
        if !library.behaviours().contains(&b.as_str()) {
            return Err(super::bad_input(anyhow::anyhow!(
                "--shot-model maps:{b}: {} has no behaviour \"{b}\"; it has: {}",
                library.source,
                library.behaviours().join(", ")
            )));
        }
    }
    let caps = args.capability.build_with(&library, &captures)?;
    let params = DecisionParams {
        shot_time_s: args.shot_time,
        epsilon_s: args.epsilon,
        ..DecisionParams::default()
    };
    let model = match &args.shot_model {
        ModelSpec::Own => caps.defender(args.defense),
        ModelSpec::Maps(b) => caps.by_behaviour(b).expect("built above"),
        other => {
            return Err(super::bad_input(anyhow::anyhow!(
                "--shot-model {}: basketball-decide models the defender with maps (own, paper or \
                 maps:BEHAVIOUR); basketball-eval fits and plays kinematic and isotropic models",
                other.name()
            )))
        }
    };
    let defenders = standing(model, &args.defender);
    let shot = ShotModel::default();
    let decision = Situation {
        court: &court,
        shot: &shot,
        params: &params,
        shooter: caps.dribble.reach(&args.shooter, Motion::Still),
        defenders: &defenders,
        shot_clock_s: GameParams::default().shot_clock_s,
    }
    .decide();
    if let Some(file) = &args.png {
        picture::decision(&court, &decision, &params, &args, file)?;
    }
    // C_o of every candidate by the defender's own map: the truth the model stands for.
    let truth = standing(caps.defender(args.defense), &args.defender);
    let c_o_own: Vec<f64> = decision
        .candidates
        .iter()
        .map(|c| {
            let at = glam::DVec2::from_array(c.cell);
            truth
                .iter()
                .map(|d| d.seconds(at))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let safe_by = |c_o: f64, c: &fieldhouse::basketball::Candidate| {
        c_o > c.c_d + params.shot_time_s + params.epsilon_s
    };
    // Squares the model calls safe that the defender reaches in time, and the reverse.
    let (falsely_safe, falsely_unsafe) =
        decision
            .candidates
            .iter()
            .zip(&c_o_own)
            .fold((0u64, 0u64), |(fs, fu), (c, &truth)| {
                let (model, real) = (c.qualifies(&params), safe_by(truth, c));
                (
                    fs + u64::from(model && !real),
                    fu + u64::from(!model && real),
                )
            });
    if args.json {
        let doc = json!({
            "chosen": decision.chosen,
            "candidates": decision.candidates,
            "qualifying": decision.candidates.iter().filter(|c| c.qualifies(&params)).count(),
            "horizon_s": model.horizon_s(),
            "shot_model": args.shot_model.name(),
            "defense": args.defense.name(),
            "c_o_own_s": c_o_own,
            "model_safe_but_reached": falsely_safe,
            "model_unsafe_but_safe": falsely_unsafe,
            "motion_source": caps.source.to_string(),
            "court": court,
            "shot": shot,
        });
        writeln!(out, "{doc}")?;
        return Ok(());
    }
    let qualifying = decision
        .candidates
        .iter()
        .filter(|c| c.qualifies(&params))
        .count();
    writeln!(
        out,
        "{} of {} {} C_o > C_d + T_s + ε (T_s {} s, ε {} s; motion: {})",
        qualifying,
        plural(decision.candidates.len() as u64, "reachable square"),
        if qualifying == 1 {
            "satisfies"
        } else {
            "satisfy"
        },
        figure(params.shot_time_s, 3),
        figure(params.epsilon_s, 3),
        caps.source
    )?;
    match decision.chosen {
        Some(c) => writeln!(
            out,
            "shoot from ({:.2}, {:.2}){}: success {:.2}; defender needs {:.2} s > {:.2} s dribble + {} s shot + {} s margin",
            c.cell[0],
            c.cell[1],
            if c.here { " (here)" } else { "" },
            c.success,
            c.c_o,
            c.c_d,
            figure(c.t_s, 3),
            figure(c.epsilon, 3)
        )?,
        None => writeln!(out, "no square qualifies: fall back to the plan (maneuver, pass when pressed)")?,
    }
    let chosen_own = decision.chosen.and_then(|chosen| {
        let k = decision
            .candidates
            .iter()
            .position(|c| c.cell == chosen.cell)?;
        Some(c_o_own[k])
    });
    writeln!(
        out,
        "the defender's own map ({}){}: the model calls {} safe that the defender reaches in time, and {} unsafe that it does not",
        args.defense.name(),
        chosen_own.map_or(String::new(), |s| format!(" gives the chosen square C_o {s:.2} s")),
        plural(falsely_safe, "square"),
        plural(falsely_unsafe, "square"),
    )?;
    Ok(())
}
