//! Fielders who catch fly balls from what they see: their bodies, the catch test, the
//! strategies from the catching literature, single trials and sweeps over many launches.

mod body;
mod catch_zone;
mod fielder;
mod observer;
#[cfg(test)]
mod oracles;
mod path_shape;
pub mod strategy;
mod sweep;
mod terminal;
mod trial;

pub use body::{Body, Limits};
pub use catch_zone::CatchZone;
pub(crate) use fielder::Fielder;
pub use fielder::{FielderConfig, Step};
pub use observer::Observer;
pub(crate) use path_shape::OpticalFit;
pub use path_shape::{PathShape, RunWatch, SignatureSummary, Signatures};
pub use strategy::{Brain, Forecast, LotReference, StrategyKind};
pub use sweep::{
    FinishingEffect, LaunchDistribution, SpareBin, StrategySummary, Sweep, SweepCase, SweepReport,
    SPARE_BINS_S,
};
pub use trial::{forecast, Outcome, TraceEntry, Trial, TrialConfig, TrialResult};
