//! `fieldhouse basketball-decide`: one opponent-modelling decision, every square shown;
//! and where the basketball commands get their motion and cached maps.

use super::args::{ground_pose, non_negative, parse_str};
use super::canvas::{hot, text_width, Canvas, Rgb, INK, LINE_PX};
use super::costmap::CacheArgs;
use super::heatmap::UNREACHABLE;
use super::model_spec::ModelSpec;
use super::motion::MotionSourceArgs;
use anyhow::Context;
use clap::Args;
use fieldhouse::basketball::{
    Capabilities, Court, Decision, DecisionParams, DefenderMotion, GameParams, Motion, Mover,
    Opponent, ShotModel, Situation,
};
use fieldhouse::costmap::AgentPose;
use fieldhouse::words::{figure, plural};
use glam::DVec2;
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
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
        let reuse = self.cache.reuse(cache.as_deref());
        let mut caps = Capabilities::build(library, reuse, &mut progress)
            .context("building the basketball behaviours (run, dribble, defense)")?;
        for name in captures {
            caps = caps
                .with_capture(library, name, reuse, &mut progress)
                .with_context(|| format!("building the behaviour {name}"))?;
        }
        tracing::info!(
            elapsed_s = %figure(started.elapsed().as_secs_f64(), 2),
            cache = %cache.map_or_else(|| "none".to_string(), |d| d.display().to_string()),
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
        picture(&court, &decision, &params, &args, file)?;
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

/// Pixels per court square.
const SCALE: f64 = 16.0;
const SHOOTER: Rgb = [40, 200, 60];
const DEFENDER: Rgb = [230, 40, 40];
const BASKET: Rgb = [255, 140, 0];
const FAILS: Rgb = [120, 120, 120];
const LINE: Rgb = [40, 90, 200];
const GAP: usize = 12;

/// Three court panels from above (x right, z down): the shooter's dribbling time C_d,
/// the defender's time C_o, and the rule (qualifying squares by success, dark = better;
/// the rest grey; the chosen square outlined in green).
fn picture(
    court: &Court,
    decision: &Decision,
    params: &DecisionParams,
    args: &DecideArgs,
    file: &Path,
) -> anyhow::Result<()> {
    let (nx, nz) = court.squares_xz();
    let (w, h) = (nx as f64 * SCALE, nz as f64 * SCALE);
    let mut canvas = Canvas::new(3 * w as usize + 2 * GAP, h as usize, [255, 255, 255]);
    let horizon = decision
        .candidates
        .iter()
        .map(|c| c.c_o.max(c.c_d))
        .fold(0.1, f64::max);
    let best = decision
        .candidates
        .iter()
        .map(|c| c.success)
        .fold(1e-9, f64::max);
    let half_z = 0.5 * nz as f64 * court.square_m;
    let px = |panel: usize, p: DVec2| {
        DVec2::new(
            panel as f64 * (w + GAP as f64) + p.x / court.square_m * SCALE,
            (p.y + half_z) / court.square_m * SCALE,
        )
    };
    for panel in 0..3 {
        canvas.fill(
            px(panel, DVec2::new(0.0, -half_z)),
            px(panel, DVec2::new(court.length_m, half_z)),
            UNREACHABLE,
        );
    }
    let half = DVec2::splat(0.5 * court.square_m);
    for c in &decision.candidates {
        let centre = DVec2::from_array(c.cell);
        let colours = [
            hot(c.c_d / horizon),
            hot(c.c_o / horizon),
            if c.qualifies(params) {
                hot(1.0 - c.success / best)
            } else {
                FAILS
            },
        ];
        for (panel, colour) in colours.into_iter().enumerate() {
            canvas.fill(px(panel, centre - half), px(panel, centre + half), colour);
        }
    }
    for panel in 0..3 {
        // The three-point arc, where it lies on the court.
        for k in 0..=720 {
            let a = (f64::from(k) / 720.0 - 0.5) * std::f64::consts::PI;
            let p = court.basket + DVec2::from_angle(a) * court.three_point_m;
            if court.contains(p) {
                canvas.disc(px(panel, p), 1.0, LINE);
            }
        }
        canvas.disc(px(panel, court.basket), 0.45 * SCALE, BASKET);
        let pose = |p: &AgentPose, colour: Rgb, canvas: &mut Canvas| {
            canvas.disc(px(panel, p.position), 0.3 * SCALE, colour);
            canvas.arrow(
                px(panel, p.position),
                DVec2::from_angle(p.heading),
                2.0 * SCALE,
                colour,
            );
        };
        pose(&args.shooter, SHOOTER, &mut canvas);
        for d in &args.defender {
            pose(d, DEFENDER, &mut canvas);
        }
    }
    if let Some(c) = decision.chosen {
        let centre = DVec2::from_array(c.cell);
        canvas.outline(
            px(2, centre - half * 3.0),
            px(2, centre + half * 3.0),
            3,
            SHOOTER,
        );
    }
    annotate(canvas, (w, h), horizon, params).save(file)
}

/// The three panels (each `panel` wide and high, px) under their titles, over the time
/// scale (0 to `horizon_s`) and a legend: the file explains itself.
fn annotate(panels: Canvas, panel: (f64, f64), horizon_s: f64, params: &DecisionParams) -> Canvas {
    let (panel_w, panel_h) = panel;
    const PAD: f64 = 6.0;
    let top = LINE_PX + 2.0 * PAD;
    let mut canvas = panels.with_margins(top as usize, 70, 0, [255, 255, 255]);
    let titles = [
        "C_d: shooter's dribbling time",
        "C_o: defenders' time",
        "the rule: safe squares",
    ];
    for (k, title) in titles.into_iter().enumerate() {
        let left = k as f64 * (panel_w + GAP as f64);
        canvas.text(
            DVec2::new(left + 0.5 * (panel_w - text_width(title)).max(0.0), PAD),
            title,
            INK,
        );
    }
    let below = top + panel_h + PAD;
    let bar_w = (2.0 * panel_w + GAP as f64 - 2.0 * PAD).min(420.0);
    canvas.hot_bar(
        DVec2::new(PAD, below),
        DVec2::new(bar_w, 14.0),
        "0 s",
        &format!("{horizon_s:.1} s (C_d, C_o)"),
    );
    let rule = format!(
        "not safe: C_o <= C_d + {} s + {} s",
        params.shot_time_s, params.epsilon_s
    );
    canvas.legend(
        DVec2::new(PAD, below + 14.0 + LINE_PX + 2.0 * PAD),
        &[
            (FAILS, rule.as_str()),
            (hot(0.0), "safe, best shot (darker is better)"),
            (SHOOTER, "shooter; chosen square"),
            (UNREACHABLE, "beyond the map"),
            (DEFENDER, "defender"),
            (BASKET, "basket"),
        ],
    );
    canvas
}
