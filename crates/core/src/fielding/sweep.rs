//! Many launches, every strategy on the same balls: the experiment that compares the
//! catching theories.

use super::trial::{forecast, Trial, TrialConfig, TrialResult};
use super::{Observer, SignatureSummary, Signatures, StrategyKind};
use crate::physics::{AirModel, BallSpec, Flight, Launch};
use glam::DVec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

/// Longest flight simulated; every launch in range lands well before.
const MAX_FLIGHT_S: f64 = 20.0;

/// The launches of a sweep and where fielders start. Every range is uniform.
///
/// The defaults are outfield fly balls: 25–45 m/s off the bat (56–100 mph), 25–65° above
/// the horizontal, anywhere in fair territory (azimuth 0–90°), 1000–3000 rpm of backspin,
/// hit from 1 m; the fielder starts 10–40 m from where the ball comes down, in a
/// uniformly random direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LaunchDistribution {
    /// Launch speed range, m/s.
    pub(crate) speed_m_s: (f64, f64),
    /// Elevation range, degrees above the horizontal.
    pub(crate) elevation_deg: (f64, f64),
    /// Azimuth range, degrees from +x toward +z.
    pub(crate) azimuth_deg: (f64, f64),
    /// Backspin range, rpm.
    pub(crate) spin_rpm: (f64, f64),
    /// Height every ball leaves the bat at, m.
    pub(crate) launch_height_m: f64,
    /// Range of the fielder's start distance from the landing point, m.
    pub(crate) fielder_distance_m: (f64, f64),
}

impl Default for LaunchDistribution {
    fn default() -> Self {
        LaunchDistribution {
            speed_m_s: (25.0, 45.0),
            elevation_deg: (25.0, 65.0),
            azimuth_deg: (0.0, 90.0),
            spin_rpm: (1000.0, 3000.0),
            launch_height_m: 1.0,
            fielder_distance_m: (10.0, 40.0),
        }
    }
}

/// One launch of a sweep with the fielder's start.
#[derive(Debug, Clone)]
pub struct SweepCase {
    /// The ball's launch.
    pub launch: Launch,
    /// Where the fielder starts, (x, z) in m.
    pub start: DVec2,
    /// The launch flown to the ground.
    pub flight: Flight,
}

/// The physical setting shared by all launches of a sweep.
#[derive(Debug, Clone, Copy)]
pub struct Sweep {
    /// The ball flown.
    pub ball: BallSpec,
    /// The forces on it besides gravity.
    pub air: AirModel,
    /// Air density, kg/m³.
    pub air_density: f64,
    /// The tick, s.
    pub dt: f64,
    /// The fielder and catch zone of every trial, before the observer's senses and
    /// reach are applied.
    pub trial: TrialConfig,
    /// Who watches: its delay, noise, smoothing and reach replace the trial's.
    pub observer: Observer,
}

/// What one strategy did over a whole sweep.
#[derive(Debug, Clone, Serialize)]
pub struct StrategySummary {
    /// The strategy summarised.
    pub strategy: StrategyKind,
    /// Trials run: one per case.
    pub(crate) trials: usize,
    /// Trials that ended in a catch.
    pub caught: usize,
    /// `caught / trials` (0 without trials).
    pub catch_rate: f64,
    /// Balls the `predictive` fielder caught, and this strategy's share of them.
    pub catchable: usize,
    pub(crate) caught_catchable: usize,
    /// `caught_catchable / catchable` (0 when no ball was catchable).
    pub catchable_rate: f64,
    /// Mean over trials of each trial's peak acceleration, m/s².
    pub mean_peak_accel: f64,
    /// Largest peak acceleration of any trial, m/s².
    pub max_peak_accel: f64,
    /// Mean over trials of each trial's time-averaged |a|, m/s².
    pub mean_accel: f64,
    /// Mean over trials of each trial's peak speed, m/s.
    pub mean_peak_speed: f64,
    /// Largest peak speed of any trial, m/s.
    pub max_peak_speed: f64,
    /// Share of trials whose path was straight (see `PathShape`).
    pub share_straight: f64,
    /// Share of trials whose path bulged toward home plate.
    pub share_bulging_toward_home: f64,
    /// Share of trials whose path bulged away from home plate.
    pub share_bulging_away_from_home: f64,
    /// Median over trials of the path's bulge: its largest deviation from the chord as a
    /// share of the chord, positive toward home (see `path_shape::bulge`).
    pub median_bulge: f64,
    /// Catchable balls and this strategy's catches of them, by the time the ball left
    /// to spare (see [`SPARE_BINS_S`]): where a strategy fails.
    pub by_time_to_spare: Vec<SpareBin>,
    /// Median over trials of how much d(tan ψ)/dt changed, relative to its mean: OAC's
    /// signature is 0 (see `OpticalFit`).
    pub median_rate_drift: f64,
    /// Median over trials of the image path's bend: LOT's signature is 0 (see
    /// `OpticalFit`).
    pub median_image_bend: f64,
    /// Median over trials of how far the ball's bearing from the fielder turned, degrees:
    /// the constant-bearing signature of Chapman's lateral law is 0.
    pub median_bearing_sweep_deg: f64,
    /// What the finishing phase decided, when the observer has one: each trial run again
    /// without it (no terminal run, no lunge) on the same noise.
    pub finishing: Option<FinishingEffect>,
}

/// Catches the finishing phase made and lost: the same trials with and without it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FinishingEffect {
    /// Balls caught with the finishing phase and missed without it.
    pub decided: usize,
    /// Balls missed with it and caught without it.
    pub lost: usize,
}

/// The upper edges of the time-to-spare bins, s (the last bin has none). A ball's time to
/// spare is its time to the catch band (where `predictive` is told it comes down) less
/// the fastest sprint to within reach of that point: how much slack a perfect fielder
/// has. Negative for balls caught only elsewhere in the band.
pub const SPARE_BINS_S: [f64; 3] = [0.25, 0.5, 1.0];

/// Catchable balls whose time to spare is in `[from_s, to_s)`, and how many a strategy
/// caught.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpareBin {
    /// Lower edge, s (`null`: no lower edge).
    pub from_s: Option<f64>,
    /// Upper edge, s (`null`: no upper edge).
    pub to_s: Option<f64>,
    /// Catchable balls in the bin.
    pub catchable: usize,
    /// Of those, the ones this strategy caught.
    pub caught: usize,
}

/// The bin of a time to spare: an index into [`SPARE_BINS_S`]'s bins.
fn spare_bin(spare_s: f64) -> usize {
    SPARE_BINS_S
        .iter()
        .take_while(|&&edge| spare_s >= edge)
        .count()
}

/// A sweep's result: every strategy's summary over the same cases.
#[derive(Debug, Clone, Serialize)]
pub struct SweepReport {
    /// Cases (launches) in the sweep.
    pub n: usize,
    /// The seed the cases were drawn with.
    pub seed: u64,
    /// What the cases were drawn from.
    pub(crate) distribution: LaunchDistribution,
    /// Who watched.
    pub observer: Observer,
    /// One summary per strategy, in the order asked for.
    pub strategies: Vec<StrategySummary>,
}

/// The few numbers a sweep keeps of each trial.
#[derive(Debug, Clone, Copy)]
struct Tally {
    caught: bool,
    /// The case's time-to-spare bin.
    spare_bin: usize,
    peak_accel: f64,
    peak_speed: f64,
    mean_accel: f64,
    signatures: Signatures,
    /// Whether the same trial without the finishing phase caught the ball (`None` when
    /// the observer has none).
    caught_without_finishing: Option<bool>,
}

impl Sweep {
    /// `n` cases drawn from `dist` with a portable seeded RNG, so a seed names a sweep.
    /// The draws are sequential (that fixes the cases); the flights, which cost more than
    /// everything else here, are flown in parallel.
    pub fn cases(&self, dist: &LaunchDistribution, n: usize, seed: u64) -> Vec<SweepCase> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut uniform = |(lo, hi): (f64, f64)| if hi > lo { rng.gen_range(lo..hi) } else { lo };
        let draws: Vec<(Launch, DVec2)> = (0..n)
            .map(|_| {
                let launch = Launch {
                    speed_m_s: uniform(dist.speed_m_s),
                    elevation_deg: uniform(dist.elevation_deg),
                    azimuth_deg: uniform(dist.azimuth_deg),
                    height_m: dist.launch_height_m,
                    spin_rpm: uniform(dist.spin_rpm),
                    spin_tilt_deg: 0.0,
                };
                let distance = uniform(dist.fielder_distance_m);
                let bearing = uniform((0.0, std::f64::consts::TAU));
                (launch, distance * DVec2::from_angle(bearing))
            })
            .collect();
        draws
            .into_par_iter()
            .map(|(launch, from_landing)| {
                let flight = self.fly(&launch);
                let landing = DVec2::new(flight.landing.pos.x, flight.landing.pos.z);
                SweepCase {
                    launch,
                    start: landing + from_landing,
                    flight,
                }
            })
            .collect()
    }

    /// The free flight of `launch` in this sweep's ball and air, sampled every `dt`.
    pub fn fly(&self, launch: &Launch) -> Flight {
        let air = launch.air(self.air, self.air_density, &self.ball);
        Flight::simulate(launch.initial_state(), &air, self.dt, MAX_FLIGHT_S)
    }

    /// The trial configuration with the observer's senses and reach.
    pub fn config(&self) -> TrialConfig {
        let mut config = self.trial;
        self.observer.apply(&mut config);
        config
    }

    /// Runs one strategy on one case. Noise (if any) is seeded by the case and strategy.
    pub fn trial(
        &self,
        case_index: usize,
        case: &SweepCase,
        strategy: StrategyKind,
        record_trace: bool,
    ) -> TrialResult {
        self.trial_with(self.config(), case_index, case, strategy, record_trace)
    }

    /// [`Self::trial`] with `config` for the sweep's own.
    fn trial_with(
        &self,
        config: TrialConfig,
        case_index: usize,
        case: &SweepCase,
        strategy: StrategyKind,
        record_trace: bool,
    ) -> TrialResult {
        let mut config = TrialConfig {
            record_trace,
            ..config
        };
        config.fielder.noise_seed ^= (case_index as u64) << 8 | strategy as u64;
        Trial {
            flight: &case.flight,
            config: &config,
        }
        .run(strategy, case.start)
    }

    /// Every strategy on every case, in parallel across cases; the report is the same
    /// whatever the number of threads.
    pub fn run(
        &self,
        cases: &[SweepCase],
        strategies: &[StrategyKind],
        dist: &LaunchDistribution,
        seed: u64,
    ) -> SweepReport {
        let zone = self.config().zone;
        // The same trials without the finishing phase, when there is one.
        let unfinished = (self.observer.terminal_s > 0.0).then(|| {
            let mut config = self.config();
            config.fielder.terminal_s = 0.0;
            config.zone.lunge_m = 0.0;
            config
        });
        let tallies: Vec<(bool, Vec<Tally>)> = cases
            .par_iter()
            .enumerate()
            .map(|(i, case)| {
                let catchable = self
                    .trial(i, case, StrategyKind::Predictive, false)
                    .outcome
                    .caught;
                let band = forecast(&case.flight, &zone);
                let run = (band.point - case.start).length() - zone.reach_m;
                let spare_bin = spare_bin(band.t - self.trial.fielder.limits.sprint_time(run));
                let tallies = strategies
                    .iter()
                    .map(|&s| {
                        let r = self.trial(i, case, s, false);
                        let home =
                            DVec2::new(case.flight.samples[0].pos.x, case.flight.samples[0].pos.z);
                        Tally {
                            caught: r.outcome.caught,
                            spare_bin,
                            peak_accel: r.peak_accel,
                            peak_speed: r.peak_speed,
                            mean_accel: r.mean_accel,
                            signatures: Signatures::of(&r.path, home, &r.optical),
                            caught_without_finishing: unfinished.map(|config| {
                                self.trial_with(config, i, case, s, false).outcome.caught
                            }),
                        }
                    })
                    .collect();
                (catchable, tallies)
            })
            .collect();
        let strategies = strategies
            .iter()
            .enumerate()
            .map(|(k, &strategy)| summarise(strategy, tallies.iter().map(|(c, t)| (*c, &t[k]))))
            .collect();
        SweepReport {
            n: cases.len(),
            seed,
            distribution: *dist,
            observer: self.observer,
            strategies,
        }
    }
}

fn summarise<'a>(
    strategy: StrategyKind,
    tallies: impl Iterator<Item = (bool, &'a Tally)>,
) -> StrategySummary {
    let tallies: Vec<(bool, &Tally)> = tallies.collect();
    let n = tallies.len();
    let count = |f: &dyn Fn(bool, &Tally) -> bool| tallies.iter().filter(|(c, t)| f(*c, t)).count();
    let caught = count(&|_, t| t.caught);
    let catchable = count(&|c, _| c);
    let caught_catchable = count(&|c, t| c && t.caught);
    let mean = |f: &dyn Fn(&Tally) -> f64| {
        tallies.iter().map(|(_, t)| f(t)).sum::<f64>() / n.max(1) as f64
    };
    let max = |f: &dyn Fn(&Tally) -> f64| tallies.iter().map(|(_, t)| f(t)).fold(0.0, f64::max);
    let signatures: Vec<Signatures> = tallies.iter().map(|(_, t)| t.signatures).collect();
    let shapes = SignatureSummary::of(&signatures);
    let median = |m: Option<f64>| m.unwrap_or(f64::NAN);
    let rate = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    let by_time_to_spare = (0..=SPARE_BINS_S.len())
        .map(|k| SpareBin {
            from_s: k.checked_sub(1).map(|j| SPARE_BINS_S[j]),
            to_s: SPARE_BINS_S.get(k).copied(),
            catchable: count(&|c, t| c && t.spare_bin == k),
            caught: count(&|c, t| c && t.caught && t.spare_bin == k),
        })
        .collect();
    StrategySummary {
        strategy,
        trials: n,
        caught,
        catch_rate: rate(caught, n),
        catchable,
        caught_catchable,
        catchable_rate: rate(caught_catchable, catchable),
        mean_peak_accel: mean(&|t| t.peak_accel),
        max_peak_accel: max(&|t| t.peak_accel),
        mean_accel: mean(&|t| t.mean_accel),
        mean_peak_speed: mean(&|t| t.peak_speed),
        max_peak_speed: max(&|t| t.peak_speed),
        share_straight: shapes.share_straight,
        share_bulging_toward_home: shapes.share_bulging_toward_home,
        share_bulging_away_from_home: shapes.share_bulging_away_from_home,
        median_bulge: median(shapes.median_bulge),
        by_time_to_spare,
        median_rate_drift: median(shapes.median_rate_drift),
        median_image_bend: median(shapes.median_image_bend),
        median_bearing_sweep_deg: median(shapes.median_bearing_sweep_deg),
        finishing: tallies
            .iter()
            .all(|(_, t)| t.caught_without_finishing.is_some())
            .then(|| FinishingEffect {
                decided: count(&|_, t| t.caught && t.caught_without_finishing == Some(false)),
                lost: count(&|_, t| !t.caught && t.caught_without_finishing == Some(true)),
            })
            .filter(|_| n > 0),
    }
}
