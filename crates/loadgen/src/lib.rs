//! `fieldhouse loadgen`: spectator load against fieldhouse, against the bare sender (the
//! least any server must do to send the same frames: see [`bare`]) and against a peer (a
//! Colyseus 0.18 server holding an equivalent state), all started here on loopback, so
//! a team choosing a game server can compare them on one machine, and fieldhouse's cost
//! can be read against the floor.
//!
//! For each spectator count, each server in turn (fieldhouse, the bare sender, the
//! peer): start it, connect the spectators (at most [`CONNECTING_AT_ONCE`] handshakes at
//! a time), let them settle, then measure a window of `seconds`. Reported per server:
//!
//! * delivered share: messages received ÷ (spectators × messages published in the
//!   window), a message counting as published when any spectator received it (a
//!   fieldhouse frame is known by its tick, a Colyseus patch by its bytes). A stamped
//!   frame (fieldhouse's, the bare sender's) is in the window if its `sent_us` is, and
//!   counts as delivered if it arrives within a second (`RECORD_AROUND`) of the window's end; an
//!   unstamped message (Colyseus's) is placed by its first arrival at any spectator, so
//!   every copy of a message is in the window or out of it together;
//! * the frame rate held: the median and lowest per-spectator rate in the window;
//! * latency: fieldhouse's frames carry their publish time (`serve --stamp-frames`; the
//!   bare sender's too), so their latency is arrival − publish on the same clock.
//!   Colyseus patches carry none, so for every server the *fan-out spread* is reported
//!   as well: a message's arrival at each spectator minus its first arrival at any,
//!   which is what a large audience adds;
//! * bytes per message; the server's CPU time (utime + stime from /proc) per delivered
//!   message, and its ratio to the bare sender's in the same round; the server's
//!   resident memory (VmRSS, VmHWM); the load generator's own CPU is excluded, and
//!   reported; fieldhouse's tick overruns (from /metrics).
//!
//! Everything is bounded: the counts and the window are arguments, each phase has a
//! deadline, and the servers started here are killed at the end.

pub mod bare;
mod bots;
mod client;
mod procfs;
mod servers;
pub mod soak;

pub use bots::{table as bot_table, BotRound};
pub use servers::Peer;

use anyhow::Context;
use serde::Serialize;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Handshakes in flight at once while connecting spectators: enough to connect 5,000
/// in a few seconds, few enough that neither side's accept queue overflows.
pub const CONNECTING_AT_ONCE: usize = 100;

/// How long spectators record before the window and after it: a message is placed in the
/// window by when it was published (see `summarise`), and one published in the window
/// but arriving more than this after it counts as not delivered.
const RECORD_AROUND: Duration = Duration::from_secs(1);

/// The longest a round waits for its spectators to connect.
const CONNECT_WITHIN: Duration = Duration::from_secs(120);

/// What to run.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Spectator counts, each run as its own round.
    pub spectators: Vec<usize>,
    /// fieldhouse matches the spectators are spread over (the peer has one room).
    pub matches: usize,
    /// The measured window per round, seconds.
    pub seconds: f64,
    /// Time between the last spectator connecting and the window, seconds.
    pub settle_s: f64,
    /// The fieldhouse binary to start (`serve --no-demo --stamp-frames`).
    pub fieldhouse: std::path::PathBuf,
    /// The peer to run under the same load, if any.
    pub peer: Option<Peer>,
    /// Whether to run fieldhouse's spectator rounds (bot rounds always run it).
    pub fieldhouse_rounds: bool,
    /// Whether to run the bare sender under the same load (see [`bare`]).
    pub bare: bool,
}

/// One server under one load.
#[derive(Debug, Clone, Serialize)]
pub struct Round {
    pub server: &'static str,
    pub matches: usize,
    pub spectators: usize,
    pub connected: usize,
    pub window_s: f64,
    /// Messages the server published in the window, per spectator (on average over
    /// their matches).
    pub published: u64,
    pub delivered: u64,
    pub delivered_share: f64,
    pub rate_median_hz: f64,
    pub rate_min_hz: f64,
    /// Publish-to-arrival, ms (fieldhouse only: its frames carry their send time).
    pub latency_ms: Option<Percentiles>,
    /// Arrival minus the first arrival of the same message at any spectator, ms.
    pub spread_ms: Percentiles,
    pub bytes_per_message: f64,
    pub server_cpu_s: f64,
    /// The part of the server's CPU time spent in the kernel (on loopback, sending
    /// includes delivering to the receiving socket).
    pub server_kernel_share: f64,
    pub server_cpu_us_per_message: f64,
    /// `server_cpu_us_per_message` ÷ the bare sender's at the same count in the same
    /// run (1 for the bare sender itself; None when it did not run, or its CPU time in
    /// the window was under the 10 ms /proc counts in).
    pub cpu_vs_bare: Option<f64>,
    pub server_rss_mb: f64,
    pub server_peak_rss_mb: f64,
    pub loadgen_cpu_s: f64,
    /// fieldhouse's tick overruns in the window (None for the peer).
    pub tick_overruns: Option<u64>,
}

#[derive(Debug, Clone, Copy, Serialize)]
pub struct Percentiles {
    pub p50: f64,
    pub p99: f64,
    pub max: f64,
}

impl Percentiles {
    /// From samples in µs, reported in ms.
    fn of(mut us: Vec<u64>) -> Percentiles {
        if us.is_empty() {
            return Percentiles {
                p50: f64::NAN,
                p99: f64::NAN,
                max: f64::NAN,
            };
        }
        us.sort_unstable();
        let at = |q: f64| us[((us.len() - 1) as f64 * q).round() as usize] as f64 / 1000.0;
        Percentiles {
            p50: at(0.5),
            p99: at(0.99),
            max: at(1.0),
        }
    }
}

/// Runs every round of the plan: at each count fieldhouse, then the bare sender, then
/// the peer.
pub fn run(plan: &Plan) -> anyhow::Result<Vec<Round>> {
    // A peer that cannot start would otherwise fail only after fieldhouse's first round.
    if let Some(peer) = &plan.peer {
        peer.check()?;
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    let mut rounds = Vec::new();
    for &n in &plan.spectators {
        let mut here: Vec<Round> = Vec::new();
        if plan.fieldhouse_rounds {
            let server = servers::Running::fieldhouse(&plan.fieldhouse, plan.matches)?;
            here.push(runtime.block_on(round(plan, &server, n))?);
        }
        if plan.bare {
            // The same payload size as fieldhouse's frames in this round.
            let size = here
                .first()
                .filter(|r| r.delivered > 0)
                .map(|r| (r.bytes_per_message.round() as usize).clamp(1, 65_535));
            let server = servers::Running::bare(&plan.fieldhouse, plan.matches, size)?;
            here.push(runtime.block_on(round(plan, &server, n))?);
        }
        if let Some(peer) = &plan.peer {
            let server = servers::Running::peer(peer)?;
            here.push(runtime.block_on(round(plan, &server, n))?);
        }
        // (None if the bare sender's CPU was too little to see: /proc counts 10 ms ticks.)
        let floor = here
            .iter()
            .find(|r| r.server == servers::BARE)
            .map(|r| r.server_cpu_us_per_message)
            .filter(|&us| us > 0.0);
        for r in &mut here {
            r.cpu_vs_bare = floor.map(|f| r.server_cpu_us_per_message / f);
        }
        rounds.extend(here);
    }
    Ok(rounds)
}

/// The bot round: `bots` bots spread over `plan.matches` lock-step matches, measured
/// over `plan.seconds` after `plan.settle_s` (see `loadgen::bots`), with `plan.spectators[0]`
/// spectators (if any) watching the same matches.
pub fn run_bots(plan: &Plan, bots: usize, think: Duration) -> anyhow::Result<BotRound> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    let (server, urls) = servers::Running::fieldhouse_bots(&plan.fieldhouse, plan.matches, bots)?;
    let load = bots::BotLoad {
        think,
        spectators: plan.spectators.first().copied().unwrap_or(0),
        seconds: plan.seconds,
        settle_s: plan.settle_s,
    };
    runtime.block_on(bots::round(&server, &urls, plan.matches, &load))
}

async fn round(plan: &Plan, server: &servers::Running, n: usize) -> anyhow::Result<Round> {
    tracing::info!(server = server.name, spectators = n, "connecting");
    let recording = Arc::new(AtomicBool::new(false));
    let stop = Arc::new(AtomicBool::new(false));
    let audience = Audience::connect(server, n, &recording, &stop).await?;
    tokio::time::sleep(Duration::from_secs_f64(plan.settle_s)).await;
    // Recording starts a little before the window: an unstamped message is placed by its
    // first arrival anywhere, which must be seen to place it before the window.
    recording.store(true, Ordering::SeqCst);
    tokio::time::sleep(RECORD_AROUND).await;
    let window = Window::measure(server, &AtomicBool::new(false), plan.seconds).await?;
    tokio::time::sleep(RECORD_AROUND).await;
    recording.store(false, Ordering::SeqCst);
    stop.store(true, Ordering::SeqCst);
    let seen = audience.logs();
    Ok(summarise(
        server.name,
        server.targets.len(),
        n,
        &seen,
        &window,
    ))
}

/// Spectators of a server's targets (spectator i watches `targets[i % len]`), logging
/// what arrives while `recording` is set, until `stop`: connected by tasks, read by a
/// few threads (see `client`).
struct Audience {
    readers: Arc<client::Readers>,
}

impl Audience {
    /// Connects `n` spectators, at most [`CONNECTING_AT_ONCE`] handshakes at a time, and
    /// returns once every handshake is done (or after [`CONNECT_WITHIN`]).
    async fn connect(
        server: &servers::Running,
        n: usize,
        recording: &Arc<AtomicBool>,
        stop: &Arc<AtomicBool>,
    ) -> anyhow::Result<Audience> {
        let readers = Arc::new(client::Readers::start(
            client::reader_threads(),
            recording,
            stop,
        )?);
        let shared = client::Shared {
            gate: Arc::new(tokio::sync::Semaphore::new(CONNECTING_AT_ONCE)),
            settled: Arc::new(AtomicUsize::new(0)),
        };
        for i in 0..n {
            let target = server.targets[i % server.targets.len()].clone();
            tokio::spawn(client::spectate(target, shared.clone(), readers.clone()));
        }
        let deadline = std::time::Instant::now() + CONNECT_WITHIN;
        while shared.settled.load(Ordering::SeqCst) < n && std::time::Instant::now() < deadline {
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        Ok(Audience { readers })
    }

    /// The logs of those that connected, once `stop` is set (the readers see it within
    /// a tenth of a second).
    fn logs(self) -> Vec<client::Log> {
        tokio::task::block_in_place(|| self.readers.logs())
    }
}

/// What a measured window cost: its length, the server's CPU and memory, the load
/// generator's own CPU, and fieldhouse's tick overruns (None for the peer).
struct Window {
    seconds: f64,
    /// The window on the wall clock, µs since the Unix epoch (the clock the servers
    /// stamp their frames with).
    from_us: u64,
    to_us: u64,
    server_cpu: procfs::Cpu,
    loadgen_cpu_s: f64,
    memory: procfs::Memory,
    tick_overruns: Option<u64>,
}

impl Window {
    /// Sets `measuring` for `seconds` and takes the server's and our own costs around it.
    async fn measure(
        server: &servers::Running,
        measuring: &AtomicBool,
        seconds: f64,
    ) -> anyhow::Result<Window> {
        let overruns_before = server.tick_overruns();
        let cpu_before = procfs::cpu(server.pid())?;
        let self_before = procfs::cpu(std::process::id())?;
        measuring.store(true, Ordering::SeqCst);
        let from_us = client::now_us();
        let started = std::time::Instant::now();
        tokio::time::sleep(Duration::from_secs_f64(seconds)).await;
        measuring.store(false, Ordering::SeqCst);
        let to_us = client::now_us();
        let seconds = started.elapsed().as_secs_f64();
        let server_cpu = procfs::cpu(server.pid())? - cpu_before;
        let loadgen_cpu_s = (procfs::cpu(std::process::id())? - self_before).total_s();
        Ok(Window {
            seconds,
            from_us,
            to_us,
            server_cpu,
            loadgen_cpu_s,
            memory: procfs::memory(server.pid())?,
            tick_overruns: server
                .tick_overruns()
                .zip(overruns_before)
                .map(|(after, before)| after - before),
        })
    }
}

fn summarise(
    server: &'static str,
    matches: usize,
    n: usize,
    logs: &[client::Log],
    window: &Window,
) -> Round {
    let Window {
        seconds: window_s,
        from_us,
        to_us,
        server_cpu,
        loadgen_cpu_s,
        memory,
        tick_overruns,
    } = *window;
    // The first arrival of each message anywhere, by its key: when it was published, as
    // near as the load generator sees it.
    let mut first = std::collections::HashMap::<u64, u64>::new();
    for a in logs.iter().flat_map(|l| &l.arrivals) {
        first
            .entry(a.key)
            .and_modify(|t| *t = (*t).min(a.at_us))
            .or_insert(a.at_us);
    }
    // A message belongs to the window if it was published in it: a stamped frame by its
    // `sent_us`, another message by its first arrival anywhere (so that every copy of a
    // message is in or out together); one published late in the window counts even if
    // it arrives after, within `RECORD_AROUND`.
    let in_window = |a: &&client::Arrival| {
        let at = a.sent_us.unwrap_or(first[&a.key]);
        (from_us..=to_us).contains(&at)
    };
    let seen: Vec<Vec<client::Arrival>> = logs
        .iter()
        .map(|l| l.arrivals.iter().filter(in_window).copied().collect())
        .collect();
    let recorded: u64 = logs.iter().map(|l| l.arrivals.len() as u64).sum();
    let bytes: u64 = logs.iter().map(|l| l.bytes).sum();
    let delivered: u64 = seen.iter().map(|l| l.len() as u64).sum();
    let mut rates: Vec<f64> = seen.iter().map(|l| l.len() as f64 / window_s).collect();
    rates.sort_by(f64::total_cmp);
    let published_keys: std::collections::HashSet<u64> =
        seen.iter().flatten().map(|a| a.key).collect();
    // Published in the window, per match: every message some spectator received. (With
    // thousands of spectators a message none of them got is not a realistic gap to
    // miss.) Matches publish at different rates when they are lock-step, so each
    // spectator is owed its own match's messages: spectator i watches match i % matches,
    // named by the top bits of a message's key (see `client::MATCH_SHIFT`).
    let mut per_match = vec![0u64; matches];
    for key in published_keys {
        if let Some(count) = per_match.get_mut((key >> client::MATCH_SHIFT) as usize) {
            *count += 1;
        }
    }
    let owed: u64 = (0..n).map(|i| per_match[i % matches]).sum();
    let published = owed / n.max(1) as u64;
    let spread = seen
        .iter()
        .flatten()
        .map(|a| a.at_us - first[&a.key])
        .collect();
    let latencies: Vec<u64> = seen
        .iter()
        .flatten()
        .filter_map(|a| a.sent_us.map(|s| a.at_us.saturating_sub(s)))
        .collect();
    Round {
        server,
        matches,
        spectators: n,
        connected: seen.len(),
        window_s,
        published,
        delivered,
        delivered_share: delivered as f64 / owed.max(1) as f64,
        rate_median_hz: rates.get(rates.len() / 2).copied().unwrap_or(0.0),
        rate_min_hz: rates.first().copied().unwrap_or(0.0),
        latency_ms: (!latencies.is_empty()).then(|| Percentiles::of(latencies)),
        spread_ms: Percentiles::of(spread),
        bytes_per_message: bytes as f64 / recorded.max(1) as f64,
        server_cpu_s: server_cpu.total_s(),
        server_kernel_share: server_cpu.system_s / server_cpu.total_s().max(1e-9),
        server_cpu_us_per_message: server_cpu.total_s() * 1e6 / delivered.max(1) as f64,
        cpu_vs_bare: None,
        server_rss_mb: memory.rss_mb,
        server_peak_rss_mb: memory.peak_rss_mb,
        loadgen_cpu_s,
        tick_overruns,
    }
}

/// The rounds as a table, then per spectator count fieldhouse's ratios to the bare
/// sender's and the peer's figures.
pub fn table(rounds: &[Round]) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<11} {:>7} {:>6} {:>6} {:>9} {:>7} {:>7} {:>24} {:>24} {:>7} {:>9} {:>7} {:>7} {:>8} {:>8} {:>8}",
        "server",
        "matches",
        "specs",
        "conn",
        "delivered",
        "rate",
        "min",
        "latency p50/p99/max ms",
        "spread p50/p99/max ms",
        "B/msg",
        "µs/msg",
        "×bare",
        "kernel",
        "RSS MB",
        "peak MB",
        "overruns"
    );
    let ms = |p: &Percentiles| format!("{:.1}/{:.1}/{:.1}", p.p50, p.p99, p.max);
    for r in rounds {
        let _ = writeln!(
            out,
            "{:<11} {:>7} {:>6} {:>6} {:>8.2}% {:>7.1} {:>7.1} {:>24} {:>24} {:>7.0} {:>9.2} {:>7} {:>6.0}% {:>8.1} {:>8.1} {:>8}",
            r.server,
            r.matches,
            r.spectators,
            r.connected,
            100.0 * r.delivered_share,
            r.rate_median_hz,
            r.rate_min_hz,
            r.latency_ms.as_ref().map_or("-".into(), ms),
            ms(&r.spread_ms),
            r.bytes_per_message,
            r.server_cpu_us_per_message,
            r.cpu_vs_bare.map_or("-".into(), |x| format!("{x:.2}")),
            100.0 * r.server_kernel_share,
            r.server_rss_mb,
            r.server_peak_rss_mb,
            r.tick_overruns.map_or("-".into(), |o| o.to_string()),
        );
    }
    let mut counts: Vec<usize> = rounds.iter().map(|r| r.spectators).collect();
    counts.dedup();
    for n in counts {
        let at_n = || rounds.iter().filter(move |r| r.spectators == n);
        let Some(ours) = at_n().find(|r| r.server == servers::FIELDHOUSE) else {
            continue;
        };
        let spectators = fieldhouse_core::words::plural(n as u64, "spectator");
        if let Some(bare) = at_n()
            .find(|r| r.server == servers::BARE)
            .filter(|b| b.server_cpu_us_per_message > 0.0)
        {
            let _ = writeln!(
                out,
                "at {spectators}, fieldhouse ÷ bare sender: server CPU per message {:.2}, delivered share {:.3}",
                ours.server_cpu_us_per_message / bare.server_cpu_us_per_message,
                ours.delivered_share / bare.delivered_share,
            );
        }
        for peer in at_n().filter(|r| r.server != servers::FIELDHOUSE && r.server != servers::BARE)
        {
            let _ = writeln!(
                out,
                "at {spectators}, fieldhouse ÷ {}: server CPU per message {:.2}, delivered share {:.3}, RSS {:.2}, bytes per message {:.2}",
                peer.server,
                ours.server_cpu_us_per_message / peer.server_cpu_us_per_message,
                ours.delivered_share / peer.delivered_share,
                ours.server_rss_mb / peer.server_rss_mb,
                ours.bytes_per_message / peer.bytes_per_message,
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{table, Percentiles, Round};

    fn round(server: &'static str, us: f64, vs_bare: f64) -> Round {
        let ms = Percentiles {
            p50: 1.0,
            p99: 2.0,
            max: 3.0,
        };
        Round {
            server,
            matches: 1,
            spectators: 1000,
            connected: 1000,
            window_s: 10.0,
            published: 300,
            delivered: 300_000,
            delivered_share: 1.0,
            rate_median_hz: 30.0,
            rate_min_hz: 30.0,
            latency_ms: Some(ms),
            spread_ms: ms,
            bytes_per_message: 511.0,
            server_cpu_s: us * 0.3,
            server_kernel_share: 0.7,
            server_cpu_us_per_message: us,
            cpu_vs_bare: Some(vs_bare),
            server_rss_mb: 60.0,
            server_peak_rss_mb: 70.0,
            loadgen_cpu_s: 2.0,
            tick_overruns: None,
        }
    }

    #[test]
    fn the_table_shows_each_servers_cpu_against_the_bare_senders() {
        let rounds = [
            round("fieldhouse", 9.0, 1.2),
            round("bare", 7.5, 1.0),
            round("colyseus", 12.0, 1.6),
        ];
        let text = table(&rounds);
        assert!(text.lines().next().unwrap().contains("×bare"), "{text}");
        assert!(
            text.contains(
                "at 1000 spectators, fieldhouse ÷ bare sender: server CPU per message 1.20"
            ),
            "{text}"
        );
        assert!(
            text.contains("at 1000 spectators, fieldhouse ÷ colyseus: server CPU per message 0.75"),
            "{text}"
        );
        assert!(!text.contains("fieldhouse ÷ bare:"), "{text}");
    }
}
