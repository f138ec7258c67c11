//! `fieldhouse soak`: a bounded churn on one server, to show that nothing leaks. For
//! `minutes`, every few seconds a match is created (baseball, cricket and basketball in
//! turn, each with a bot slot), spectators join and leave it (some closing politely,
//! some dropping the TCP connection), a bot plays its agent for a while, leaves, and
//! comes back, and the match is deleted after `MATCH_LIFETIME` (15 s). The server's resident
//! memory, open file descriptors and threads, and its own gauges (matches, sockets),
//! are sampled throughout; after the churn stops, everything must be back where it was.

use super::client::Socket;
use super::procfs;
use super::servers::{metric, Running};
use anyhow::Context;
use fieldhouse_core::words::{figure, plural};
use futures_util::{SinkExt, StreamExt};
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

/// A new match this often.
const MATCH_EVERY: Duration = Duration::from_secs(3);
/// How long each match lives before it is deleted.
const MATCH_LIFETIME: Duration = Duration::from_secs(15);
/// Spectators per match.
const SPECTATORS: u64 = 6;
/// A sample this often.
const SAMPLE_EVERY: Duration = Duration::from_secs(10);

/// One reading of the server.
#[derive(Debug, Clone, Serialize)]
pub struct Sample {
    pub at_s: f64,
    pub rss_mb: f64,
    pub fds: usize,
    pub threads: usize,
    pub matches: u64,
    pub sockets: u64,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub minutes: f64,
    pub matches_created: u64,
    pub matches_deleted: u64,
    pub spectator_sessions: u64,
    pub bot_sessions: u64,
    pub frames_received: u64,
    /// Requests refused and sockets that would not open.
    pub failures: u64,
    /// The `error` messages bots got, by code (a command for a tick already past is
    /// `stale_tick`: expected now and then in real time, not a fault).
    pub bot_errors: BTreeMap<String, u64>,
    /// After the warm-up (the first minute) and after the churn has stopped.
    pub warm: Sample,
    pub end: Sample,
    pub peak_rss_mb: f64,
    pub samples: Vec<Sample>,
}

#[derive(Default)]
struct Counts {
    created: AtomicU64,
    deleted: AtomicU64,
    spectators: AtomicU64,
    bots: AtomicU64,
    frames: AtomicU64,
    failures: AtomicU64,
    bot_errors: Mutex<BTreeMap<String, u64>>,
}

pub fn run(fieldhouse: &std::path::Path, minutes: f64) -> anyhow::Result<Report> {
    let server = Running::empty_fieldhouse(fieldhouse, 16)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(churn(&server, minutes))
}

async fn churn(server: &Running, minutes: f64) -> anyhow::Result<Report> {
    let counts = Arc::new(Counts::default());
    let start = Instant::now();
    let until = start + Duration::from_secs_f64(minutes * 60.0);
    let mut samples = vec![sample(server, start)?];
    let mut next_sample = start + SAMPLE_EVERY;
    let mut matches = Vec::new();
    let mut k = 0u64;
    while Instant::now() < until {
        let sport = ["baseball", "cricket", "basketball"][(k % 3) as usize];
        matches.push(tokio::spawn(one_match(
            server.http().to_string(),
            sport,
            k,
            counts.clone(),
        )));
        k += 1;
        tokio::time::sleep(MATCH_EVERY).await;
        if Instant::now() >= next_sample {
            samples.push(sample(server, start)?);
            next_sample += SAMPLE_EVERY;
        }
    }
    for m in matches {
        let _ = m.await;
    }
    // Let the server close what the clients left.
    tokio::time::sleep(Duration::from_secs(3)).await;
    let end = sample(server, start)?;
    samples.push(end.clone());
    let warm = samples
        .iter()
        .find(|s| s.at_s >= 60.0_f64.min(minutes * 30.0))
        .unwrap_or(&samples[0])
        .clone();
    let bot_errors = counts.bot_errors.lock().expect("not poisoned").clone();
    Ok(Report {
        minutes,
        matches_created: counts.created.load(Relaxed),
        matches_deleted: counts.deleted.load(Relaxed),
        spectator_sessions: counts.spectators.load(Relaxed),
        bot_sessions: counts.bots.load(Relaxed),
        frames_received: counts.frames.load(Relaxed),
        failures: counts.failures.load(Relaxed),
        bot_errors,
        warm,
        end,
        peak_rss_mb: procfs::memory(server.pid())?.peak_rss_mb,
        samples,
    })
}

fn sample(server: &Running, start: Instant) -> anyhow::Result<Sample> {
    let pid = server.pid();
    let gauges = server.metrics().unwrap_or_default();
    let gauge = |name: &str| metric(&gauges, name).unwrap_or(0);
    Ok(Sample {
        at_s: start.elapsed().as_secs_f64(),
        rss_mb: procfs::memory(pid)?.rss_mb,
        fds: std::fs::read_dir(format!("/proc/{pid}/fd"))?.count(),
        threads: std::fs::read_dir(format!("/proc/{pid}/task"))?.count(),
        matches: gauge("fieldhouse_matches"),
        sockets: gauge("fieldhouse_connections{role=\"spectator\"}")
            + gauge("fieldhouse_connections{role=\"bot\"}"),
    })
}

/// A match's life: created, watched, played by a bot that leaves and returns, deleted.
async fn one_match(http: String, sport: &'static str, k: u64, counts: Arc<Counts>) {
    let bot = if sport == "basketball" { "o1" } else { "cf" };
    let agents = if sport == "basketball" {
        json!([
            {"id": "o1", "team": "offense", "strategy": "costmap", "bot": true},
            {"id": "o2", "team": "offense", "strategy": "costmap"},
            {"id": "d1", "team": "defense", "strategy": "defense"}
        ])
    } else {
        json!([{"id": "cf", "strategy": "chapman", "bot": true}, {"id": "rf"}])
    };
    let body = json!({"name": "soak", "sport": sport, "seed": k, "agents": agents});
    let base = http.clone();
    let created = tokio::task::spawn_blocking(move || Running::create_at(&base, &body)).await;
    let (id, tokens) = match created {
        Ok(Ok(made)) => made,
        failed => {
            tracing::warn!(?failed, "soak: a match could not be created");
            counts.failures.fetch_add(1, Relaxed);
            return;
        }
    };
    counts.created.fetch_add(1, Relaxed);
    let ws = http.replace("http://", "ws://");
    let mut people = Vec::new();
    for s in 0..SPECTATORS {
        // Staggered stays, some past the match's deletion (those see its `end`); odd
        // ones drop the TCP connection without a close frame.
        let stay = Duration::from_millis(1000 + (s * 3100 + k * 700) % 17_000);
        let url = format!("{ws}/ws/matches/{id}");
        people.push(tokio::spawn(spectator(
            url,
            stay,
            s % 2 == 1,
            counts.clone(),
        )));
    }
    let token = tokens[bot].as_str().unwrap_or_default();
    let play = format!("{ws}/ws/matches/{id}/play?token={token}");
    let c = counts.clone();
    // The bot plays, leaves, and comes back: control handed back and resumed.
    people.push(tokio::spawn(async move {
        bot_session(&play, Duration::from_secs(4), &c).await;
        tokio::time::sleep(Duration::from_secs(1)).await;
        bot_session(&play, Duration::from_secs(5), &c).await;
    }));
    tokio::time::sleep(MATCH_LIFETIME).await;
    let deleted = tokio::task::spawn_blocking(move || Running::delete_at(&http, &id)).await;
    match deleted {
        Ok(Ok(())) => counts.deleted.fetch_add(1, Relaxed),
        failed => {
            tracing::warn!(?failed, "soak: a match could not be deleted");
            counts.failures.fetch_add(1, Relaxed)
        }
    };
    for p in people {
        let _ = p.await;
    }
}

/// Opens a socket, counting it as a session of `sessions`, or as a failure.
async fn open(url: &str, who: &str, sessions: &AtomicU64, counts: &Counts) -> Option<Socket> {
    match tokio_tungstenite::connect_async(url).await {
        Ok((socket, _)) => {
            sessions.fetch_add(1, Relaxed);
            Some(socket)
        }
        Err(e) => {
            tracing::warn!(error = %e, who, "soak: could not connect");
            counts.failures.fetch_add(1, Relaxed);
            None
        }
    }
}

async fn spectator(url: String, stay: Duration, drop_tcp: bool, counts: Arc<Counts>) {
    let Some(mut socket) = open(&url, "spectator", &counts.spectators, &counts).await else {
        return;
    };
    let until = tokio::time::Instant::now() + stay;
    while let Ok(Some(Ok(message))) = tokio::time::timeout_at(until, socket.next()).await {
        if let Message::Text(text) = message {
            if text.as_str().starts_with(r#"{"type":"frame""#) {
                counts.frames.fetch_add(1, Relaxed);
            }
        }
    }
    if !drop_tcp {
        let _ = socket.close(None).await;
    }
}

/// A bot answering each perception with `stand` for `stay`.
async fn bot_session(url: &str, stay: Duration, counts: &Counts) {
    let Some(mut socket) = open(url, "bot", &counts.bots, counts).await else {
        return;
    };
    let until = tokio::time::Instant::now() + stay;
    while let Ok(Some(Ok(Message::Text(text)))) =
        tokio::time::timeout_at(until, socket.next()).await
    {
        let Ok(message) = serde_json::from_str::<Value>(text.as_str()) else {
            continue;
        };
        match message["type"].as_str() {
            Some("perception") => {
                let command = json!({"type": "command", "tick": message["tick"], "action": {"kind": "stand"}});
                if socket
                    .send(Message::Text(command.to_string().into()))
                    .await
                    .is_err()
                {
                    break;
                }
            }
            Some("error") => {
                let code = message["code"].as_str().unwrap_or("?").to_string();
                *counts
                    .bot_errors
                    .lock()
                    .expect("not poisoned")
                    .entry(code)
                    .or_default() += 1;
            }
            _ => {}
        }
    }
    let _ = socket.close(None).await;
}

/// The report as a table, with the verdicts: memory, descriptors and threads back
/// where they were after the warm-up, and no match or socket left behind.
pub fn table(r: &Report) -> String {
    let bot_errors = if r.bot_errors.is_empty() {
        "none".to_string()
    } else {
        let each: Vec<String> = r
            .bot_errors
            .iter()
            .map(|(code, n)| format!("{code} {n}"))
            .collect();
        each.join(", ")
    };
    let mut out = format!(
        "soak: {} min, {} created and {} deleted, {} and {}, {}, {}, bot errors: {}\n\n\
         {:>7} {:>8} {:>5} {:>8} {:>8} {:>8}\n",
        figure(r.minutes, 1),
        plural(r.matches_created, "match"),
        r.matches_deleted,
        plural(r.spectator_sessions, "spectator session"),
        plural(r.bot_sessions, "bot session"),
        plural(r.frames_received, "frame"),
        plural(r.failures, "failure"),
        bot_errors,
        "t (s)",
        "RSS MB",
        "fds",
        "threads",
        "matches",
        "sockets"
    );
    for s in &r.samples {
        out += &format!(
            "{:>7.0} {:>8.1} {:>5} {:>8} {:>8} {:>8}\n",
            s.at_s, s.rss_mb, s.fds, s.threads, s.matches, s.sockets
        );
    }
    out += &format!(
        "\npeak RSS {:.1} MB; after warm-up {:.1} MB, at the end {:.1} MB ({:+.1} MB); fds {} -> {}; \
         threads {} -> {}; matches and sockets left at the end: {} and {}\n",
        r.peak_rss_mb, r.warm.rss_mb, r.end.rss_mb, r.end.rss_mb - r.warm.rss_mb, r.warm.fds,
        r.end.fds, r.warm.threads, r.end.threads, r.end.matches, r.end.sockets
    );
    out
}
