//! `fieldhouse loadgen`: spectator load on fieldhouse, the bare sender and a peer, side by
//! side; bots in lock-step, with spectators of their matches.

use clap::{Args, ValueEnum};
use fieldhouse::loadgen::{self, Peer, Plan};
use std::io::Write;
use std::path::PathBuf;

#[derive(Args, Debug)]
#[command(
    after_help = "At each spectator count, starts `fieldhouse serve --no-demo --stamp-frames` (this binary), \
    then the bare sender (this binary's hidden `bare-sender`: accepts WebSockets and writes one prebuilt \
    frame of fieldhouse's size to each, 30 times a second, and nothing else: the floor fieldhouse's CPU \
    per frame is reported against, as ×bare), then with --peer colyseus the Colyseus server in \
    bench/peers (run `npm ci --prefix bench/peers` once; it installs exactly what \
    bench/peers/package-lock.json lists, and loadgen checks it before the first round), each alone on a \
    free loopback port; spreads the spectators over --matches 60 Hz matches (30 frames a second; the \
    peer has one room); measures a window; stops everything. Needs a file-descriptor limit above the \
    spectator count (`ulimit -n`).\n\
    Example: fieldhouse loadgen --spectators 1000,5000 --seconds 10 --peer colyseus"
)]
pub(super) struct LoadgenArgs {
    /// Spectator counts, comma-separated: one round per count (at most 20,000 each;
    /// default 1000). With --bots, one count: spectators watching the bots' matches in
    /// the same window (default none).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=20_000))]
    spectators: Vec<u32>,
    /// fieldhouse matches to spread the spectators over (the peer always has one room).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    matches: u32,
    /// The measured window of each round, seconds (1 to 600).
    #[arg(long, default_value_t = 10.0, value_parser = window)]
    seconds: f64,
    /// Seconds between the last connection and the window (0 to 60).
    #[arg(long, default_value_t = 2.0, value_parser = settle)]
    settle: f64,
    /// Bots (1 to 2,000) in lock-step matches instead of spectator rounds (spread over
    /// --matches, at most 32 each), every perception answered after --think-ms; reports
    /// the tick turnaround (command sent -> next perception), and with --spectators N
    /// also N spectators of the same matches.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=2000))]
    bots: Option<u32>,
    /// With --bots: how long each bot thinks before answering, ms (0 to 1000; 0 drives
    /// the matches as fast as the machine goes, 16 is about real-time play).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=1000))]
    think_ms: u64,
    /// A peer to run under the same load, after fieldhouse, in the same run.
    #[arg(long, value_enum, default_value_t = PeerKind::None)]
    peer: PeerKind,
    /// Where the peer lives (its package.json and server script).
    #[arg(long, value_name = "DIR", default_value = "bench/peers")]
    peer_dir: PathBuf,
    /// Servers to leave out of the spectator rounds, comma-separated: `fieldhouse`,
    /// `bare` (the bare sender, the floor fieldhouse's CPU per frame is compared with).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "SERVER")]
    skip: Vec<Skip>,
    /// Print the rounds as JSON instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Skip {
    Fieldhouse,
    Bare,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum PeerKind {
    None,
    Colyseus,
}

fn window(text: &str) -> Result<f64, String> {
    seconds_within(text, 1.0, 600.0)
}

fn settle(text: &str) -> Result<f64, String> {
    seconds_within(text, 0.0, 60.0)
}

fn seconds_within(text: &str, low: f64, high: f64) -> Result<f64, String> {
    let s: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (low..=high).contains(&s) {
        Ok(s)
    } else {
        Err(format!("{s} is outside {low} to {high} seconds"))
    }
}

pub(super) fn run(args: LoadgenArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let spectators = match (&args.spectators[..], args.bots) {
        ([], None) => vec![1000],
        ([_, _, ..], Some(_)) => anyhow::bail!(
            "--spectators with --bots is one count (the spectators watching the bots' matches)"
        ),
        (counts, _) => counts.iter().map(|&n| n as usize).collect(),
    };
    let plan = Plan {
        spectators,
        matches: args.matches as usize,
        seconds: args.seconds,
        settle_s: args.settle,
        fieldhouse: std::env::current_exe()?,
        peer: match args.peer {
            PeerKind::None => None,
            PeerKind::Colyseus => Some(Peer::Colyseus { dir: args.peer_dir }),
        },
        fieldhouse_rounds: !args.skip.contains(&Skip::Fieldhouse),
        bare: !args.skip.contains(&Skip::Bare),
    };
    if let Some(bots) = args.bots {
        let bots = bots as usize;
        anyhow::ensure!(
            bots <= 32 * plan.matches && bots >= plan.matches,
            "--bots {bots} over --matches {}: each match holds 1 to 32 bots",
            plan.matches
        );
        let think = std::time::Duration::from_millis(args.think_ms);
        let round = loadgen::run_bots(&plan, bots, think)?;
        if args.json {
            writeln!(out, "{}", serde_json::to_string_pretty(&round)?)?;
        } else {
            write!(out, "{}", loadgen::bot_table(&round))?;
        }
        return Ok(());
    }
    let rounds = loadgen::run(&plan)?;
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&rounds)?)?;
    } else {
        write!(out, "{}", loadgen::table(&rounds))?;
    }
    Ok(())
}
