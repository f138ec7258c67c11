//! `fieldhouse soak`: a bounded churn of matches, spectators and bots on one server,
//! sampling its memory, descriptors and threads to show nothing leaks.

use clap::Args;
use fieldhouse::loadgen::soak;
use std::io::Write;

#[derive(Args, Debug)]
#[command(
    after_help = "Starts `fieldhouse serve --no-demo` (this binary) on a free loopback port. Every 3 s \
    a match is created (baseball, cricket, basketball in turn, each with a bot slot); six spectators \
    join and leave it (half drop the TCP connection without a close), a bot plays, leaves and comes \
    back, and the match is deleted after 15 s. Samples the server every 10 s; stops by itself.\n\
    Example: fieldhouse soak --minutes 10"
)]
pub(super) struct SoakArgs {
    /// How long to churn, minutes (0.5 to 120).
    #[arg(long, default_value_t = 10.0, value_parser = minutes)]
    minutes: f64,
    /// Print the report as JSON instead of a table.
    #[arg(long)]
    json: bool,
}

fn minutes(text: &str) -> Result<f64, String> {
    let m: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (0.5..=120.0).contains(&m) {
        Ok(m)
    } else {
        Err(format!("{m} is outside 0.5 to 120 minutes"))
    }
}

pub(super) fn run(args: SoakArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let report = soak::run(&std::env::current_exe()?, args.minutes)?;
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        write!(out, "{}", soak::table(&report))?;
    }
    Ok(())
}
