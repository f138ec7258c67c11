//! `fieldhouse bare-sender` (hidden): the floor `fieldhouse loadgen` measures fieldhouse
//! against; see `fieldhouse_loadgen::bare`.

use anyhow::Context;
use clap::Args;
use fieldhouse::loadgen::bare;

#[derive(Args, Debug)]
pub(super) struct BareArgs {
    /// Where to listen (HOST:PORT; port 0 picks a free one).
    #[arg(long, default_value = "127.0.0.1:0")]
    addr: std::net::SocketAddr,
    /// Frames a second to every connected socket (1 to 240).
    #[arg(long, default_value_t = 30.0, value_parser = frame_hz)]
    frame_hz: f64,
    /// Pad the frame's payload with trailing spaces to this many bytes (a live
    /// fieldhouse frame's size; loadgen passes the mean of those fieldhouse sent).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65_535))]
    payload_bytes: Option<u32>,
    /// Sending threads, each with its share of the sockets (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=64))]
    threads: Option<u32>,
    /// Exit when standard input closes (loadgen holds it open while it runs).
    #[arg(long)]
    exit_with_stdin: bool,
}

fn frame_hz(text: &str) -> Result<f64, String> {
    let hz: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (1.0..=240.0).contains(&hz) {
        Ok(hz)
    } else {
        Err(format!("{hz} is outside 1 to 240 frames a second"))
    }
}

pub(super) fn run(args: BareArgs) -> anyhow::Result<()> {
    if args.exit_with_stdin {
        std::thread::spawn(|| {
            let _ = std::io::copy(&mut std::io::stdin(), &mut std::io::sink());
            std::process::exit(0);
        });
    }
    let template = bare::Template::baseball(args.payload_bytes.map(|n| n as usize))?;
    let listener = std::net::TcpListener::bind(args.addr)
        .with_context(|| format!("listening on {}", args.addr))?;
    let addr = listener.local_addr()?;
    tracing::info!(
        frame_bytes = template.bytes().len(),
        "bare sender listening on ws://{addr}/"
    );
    let threads = args.threads.map_or_else(
        || std::thread::available_parallelism().map_or(2, |n| n.get()),
        |n| n as usize,
    );
    bare::serve(listener, template, args.frame_hz, threads)
}
