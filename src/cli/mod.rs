//! The command line: one subcommand per job, `--json` for one machine-readable document on
//! stdout, logs and progress on stderr.

mod args;
mod bare;
mod basketball;
mod bot;
mod canvas;
mod capability;
mod catch;
mod costmap;
mod eval;
mod glyphs;
mod heatmap;
mod loadgen;
mod model_spec;
mod motion;
mod paths;
mod plots;
mod replay;
mod run;
mod serve;
mod soak;
mod sweep;
mod writer;

use clap::{Parser, Subcommand};
use std::io::Write;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "fieldhouse",
    version,
    about = "A multi-agent team sports simulation server",
    long_about = "fieldhouse simulates team sports with agents that act on what they perceive. \
        It serves live matches (baseball and cricket fielders chasing fly balls with Chapman's \
        optical acceleration cancellation or the Linear Optical Trajectory; basketball agents \
        that move with human motion capture and model their opponent with cost maps) to a \
        browser and to bots, and runs the experiments behind them.\n\nSet FIELDHOUSE_LOG (e.g. FIELDHOUSE_LOG=debug) for more log output on stderr."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the match server: demo matches, WebSockets for spectators and bots, REST API.
    Serve(serve::ServeArgs),
    /// One fielder, one fly ball: did it catch it, and how did it run?
    Catch(catch::CatchArgs),
    /// Many fly balls, every strategy on the same balls: catch rates, efforts, path shapes.
    CatchSweep(sweep::SweepArgs),
    /// Build a behaviour's motion graph from motion capture and print its size.
    MotionGraph(motion::MotionGraphArgs),
    /// Build a behaviour's cost map: frames to reach each cell from a start state.
    Costmap(costmap::CostmapArgs),
    /// What the basketball agents can do: frames to reach squares around them, per behaviour and start state.
    Capability(capability::CapabilityCmdArgs),
    /// Where would a shooter shoot from? Opponent modelling on every square: C_o > C_d + T_s + ε.
    BasketballDecide(basketball::DecideArgs),
    /// The paper's experiment: points per possession of the simple and cost-map offenses.
    BasketballEval(eval::EvalArgs),
    /// The reference bot: connect to a match and play one agent.
    Bot(bot::BotArgs),
    /// Play a scenario file headless, as fast as possible, into a replay file.
    Run(run::RunArgs),
    /// Inspect, verify or export a replay file.
    Replay(replay::ReplayArgs),
    /// Spectator load on fieldhouse, a bare sender (the floor) and a peer (e.g. Colyseus) on loopback: delivery, latency, CPU, memory.
    Loadgen(loadgen::LoadgenArgs),
    /// Churn matches, spectators and bots on a server for a bounded time; report whether
    /// memory, descriptors and threads stay flat.
    Soak(soak::SoakArgs),
    /// The bare sender `loadgen` measures fieldhouse against: accepts WebSockets and
    /// writes one prebuilt frame to each, 30 times a second, and nothing else.
    #[command(hide = true)]
    BareSender(bare::BareArgs),
}

pub(crate) fn main() -> ExitCode {
    let cli = Cli::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_env("FIELDHOUSE_LOG")
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .with_writer(std::io::stderr)
        // Colour only on a terminal: logs piped to a file or a test stay plain text.
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let mut out = std::io::stdout().lock();
    let result = match cli.command {
        Command::Catch(args) => catch::run(args, &mut out),
        Command::CatchSweep(args) => sweep::run(args, &mut out),
        Command::MotionGraph(args) => motion::run(args, &mut out),
        Command::Costmap(args) => costmap::run(args, &mut out),
        Command::Capability(args) => capability::run(args, &mut out),
        Command::BasketballDecide(args) => basketball::decide(args, &mut out),
        Command::BasketballEval(args) => eval::run(args, &mut out),
        Command::Serve(args) => serve::run(args),
        Command::Bot(args) => bot::run(args, &mut out),
        Command::Run(args) => run::run(args, &mut out),
        Command::Replay(args) => replay::run(args, &mut out),
        Command::Loadgen(args) => loadgen::run(args, &mut out),
        Command::Soak(args) => soak::run(args, &mut out),
        Command::BareSender(args) => bare::run(args),
    }
    .and_then(|()| Ok(out.flush()?));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A reader that stopped reading (`| head`) is not an error of ours.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => match e.downcast_ref::<Outcome>() {
            Some(outcome) => {
                eprintln!("{}", outcome.message);
                ExitCode::from(outcome.code)
            }
            None => {
                eprintln!("error: {}", causes(&e));
                ExitCode::FAILURE
            }
        },
    }
}

/// An end with an exit code of its own (README, "Exit codes"): 2 for input wrong before
/// anything ran ([`bad_input`]), 3 for `replay verify` of a file cut at its end, which
/// verifies what it has, so a script can tell that from a whole file.
#[derive(Debug)]
pub(crate) struct Outcome {
    pub code: u8,
    pub message: String,
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Outcome {}

/// Marks `e` as input the user got wrong before anything ran (an argument, a setting, a
/// scenario file): exit code 2, as for the arguments clap refuses, so a script can tell
/// a mistake in what it passed from a failure while running (1).
pub(crate) fn bad_input(e: anyhow::Error) -> anyhow::Error {
    Outcome {
        code: 2,
        message: format!("error: {}", causes(&e)),
    }
    .into()
}

/// The error and its causes, joined by ": " as `{e:#}` joins them, but without a cause
/// whose text the error wrapping it already shows. Many errors put their source in
/// their own message and also return it from `source()` (ureq's and tungstenite's do,
/// and so do `#[error("...: {source}")]` enums), which `{e:#}` prints twice: "cannot
/// read X: No such file or directory (os error 2): No such file or directory (os error
/// 2)". Our own errors leave their source out of their message; this keeps the rest
/// from repeating one.
fn causes(e: &anyhow::Error) -> String {
    let texts: Vec<String> = e.chain().map(ToString::to_string).collect();
    let mut shown = vec![texts[0].as_str()];
    for pair in texts.windows(2) {
        if !pair[0].contains(pair[1].as_str()) {
            shown.push(&pair[1]);
        }
    }
    shown.join(": ")
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain()
        .filter_map(|cause| cause.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
}

#[cfg(test)]
mod tests {
    use super::causes;

    #[test]
    fn a_cause_already_in_its_wrapper_is_not_repeated() {
        let os = || std::io::Error::from(std::io::ErrorKind::NotFound);
        // A wrapper that shows its source and also returns it, like ureq's errors.
        #[derive(Debug)]
        struct Shows(std::io::Error);
        impl std::fmt::Display for Shows {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "cannot read X: {}", self.0)
            }
        }
        impl std::error::Error for Shows {
            fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
                Some(&self.0)
            }
        }
        let e = anyhow::Error::new(Shows(os())).context("loading Y");
        assert_eq!(causes(&e), format!("loading Y: cannot read X: {}", os()));
        // A plain chain keeps every cause.
        let e = anyhow::Error::new(os()).context("cannot read X");
        assert_eq!(causes(&e), format!("cannot read X: {}", os()));
    }
}
