//! A bot round of `fieldhouse loadgen --bots N`: N bots in lock-step matches, each
//! answering every perception after thinking `think_ms` (0: at once), with two times
//! measured on the load generator's clock:
//!
//! * the **tick turnaround**: in each match, from the last of its bots' commands for a
//!   tick being sent to the first perception of the next tick arriving. In lock-step a
//!   match moves on once every bot has answered, so this is the server's whole share of
//!   a tick (reading the commands, stepping the world, writing the perceptions) plus
//!   loopback both ways, and the load generator's delay in reading;
//! * each bot's **wait**: from its own command to its next perception, which also holds
//!   its teammates' thinking, as a bot author sees it.
//!
//! Bots that answer at once drive the matches as fast as the machine goes, so the times
//! are then mostly the queue of every other match's tick; bots that think for a frame's
//! time (16 ms) give the load of real-time lock-step play.
//!
//! Spectators can watch the same matches in the same window (`--spectators`): they are
//! measured as in a spectator round, and the server's CPU is then that of both loads.

use super::client::number_after;
use super::servers::Running;
use super::{Audience, Percentiles, Round, Window};
use fieldhouse_core::words::plural;
use futures_util::{SinkExt, StreamExt};
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

#[derive(Debug, Clone, Serialize)]
pub struct BotRound {
    pub matches: usize,
    pub bots: usize,
    pub connected: usize,
    pub window_s: f64,
    pub think_ms: f64,
    /// Ticks a match made per second in the window (median over matches): lock-step
    /// matches go at their bots' pace.
    pub ticks_per_s_median: f64,
    /// A match's last command for a tick sent → its next perception received, ms.
    pub turnaround_ms: Percentiles,
    /// A bot's command sent → its next perception received, ms.
    pub bot_wait_ms: Percentiles,
    pub commands: u64,
    pub server_cpu_s: f64,
    pub server_cpu_us_per_command: f64,
    pub server_rss_mb: f64,
    pub loadgen_cpu_s: f64,
    /// The spectators watching the bots' matches in the same window, if any.
    pub spectators: Option<Round>,
}

/// One bot's measurements in the window.
#[derive(Default)]
struct Seen {
    waits_us: Vec<u64>,
    /// (tick, when its perception arrived) and (tick, when the command for it was sent).
    arrived: Vec<(u64, Instant)>,
    answered: Vec<(u64, Instant)>,
    commands: u64,
    first_tick: Option<u64>,
    last_tick: u64,
}

/// What a bot round runs: `think` per perception, and `spectators` watching.
pub(super) struct BotLoad {
    pub think: Duration,
    pub spectators: usize,
    pub seconds: f64,
    pub settle_s: f64,
}

pub(super) async fn round(
    server: &Running,
    urls: &[(usize, String)],
    matches: usize,
    load: &BotLoad,
) -> anyhow::Result<BotRound> {
    let BotLoad {
        think,
        spectators,
        seconds,
        settle_s,
    } = *load;
    let measuring = Arc::new(AtomicBool::new(false));
    let recording = Arc::new(AtomicBool::new(false));
    let stop = Arc::new(AtomicBool::new(false));
    let audience = Audience::connect(server, spectators, &recording, &stop).await?;
    let tasks: Vec<_> = urls
        .iter()
        .map(|(m, url)| {
            let (url, measuring, stop) = (url.clone(), measuring.clone(), stop.clone());
            let m = *m;
            tokio::spawn(async move { (m, play(&url, think, &measuring, &stop).await) })
        })
        .collect();
    tokio::time::sleep(Duration::from_secs_f64(settle_s.max(1.0))).await;
    recording.store(true, Ordering::SeqCst);
    let window = Window::measure(server, &measuring, seconds).await?;
    if spectators > 0 {
        tokio::time::sleep(super::RECORD_AROUND).await;
    }
    recording.store(false, Ordering::SeqCst);
    stop.store(true, Ordering::SeqCst);
    let logs = audience.logs();
    let mut waits = Vec::new();
    let mut commands = 0;
    // Per match and tick: the first perception's arrival, the last command's sending.
    let mut first_arrival = vec![std::collections::HashMap::<u64, Instant>::new(); matches];
    let mut last_answer = vec![std::collections::HashMap::<u64, Instant>::new(); matches];
    let mut connected = 0;
    // Per match, the ticks its bots saw in the window (the most any of them saw).
    let mut ticks = vec![0u64; matches];
    for task in tasks {
        if let Ok((m, Some(seen))) = task.await {
            connected += 1;
            commands += seen.commands;
            waits.extend(seen.waits_us);
            for (tick, at) in seen.arrived {
                let first = first_arrival[m].entry(tick).or_insert(at);
                *first = (*first).min(at);
            }
            for (tick, at) in seen.answered {
                let last = last_answer[m].entry(tick).or_insert(at);
                *last = (*last).max(at);
            }
            if let Some(first) = seen.first_tick {
                ticks[m] = ticks[m].max(seen.last_tick - first);
            }
        }
    }
    let turnarounds = last_answer
        .iter()
        .zip(&first_arrival)
        .flat_map(|(answers, arrivals)| {
            answers.iter().filter_map(|(tick, sent)| {
                let next = arrivals.get(&(tick + 1))?;
                Some(next.saturating_duration_since(*sent).as_micros() as u64)
            })
        })
        .collect();
    let mut rates: Vec<f64> = ticks.iter().map(|&t| t as f64 / window.seconds).collect();
    rates.sort_by(f64::total_cmp);
    Ok(BotRound {
        matches,
        bots: urls.len(),
        connected,
        window_s: window.seconds,
        think_ms: think.as_secs_f64() * 1000.0,
        ticks_per_s_median: rates.get(rates.len() / 2).copied().unwrap_or(0.0),
        turnaround_ms: Percentiles::of(turnarounds),
        bot_wait_ms: Percentiles::of(waits),
        commands,
        server_cpu_s: window.server_cpu.total_s(),
        server_cpu_us_per_command: window.server_cpu.total_s() * 1e6 / commands.max(1) as f64,
        server_rss_mb: window.memory.rss_mb,
        loadgen_cpu_s: window.loadgen_cpu_s,
        spectators: (spectators > 0)
            .then(|| super::summarise(server.name, matches, spectators, &logs, &window)),
    })
}

/// Plays one agent: every perception answered with `stand` after `think`.
async fn play(
    url: &str,
    think: Duration,
    measuring: &AtomicBool,
    stop: &AtomicBool,
) -> Option<Seen> {
    let mut socket = match tokio_tungstenite::connect_async(url).await {
        Ok((socket, _)) => socket,
        Err(e) => {
            tracing::warn!(error = %e, "a bot could not connect");
            return None;
        }
    };
    let mut seen = Seen::default();
    let mut answered_at: Option<Instant> = None;
    while !stop.load(Ordering::Relaxed) {
        let next = tokio::time::timeout(Duration::from_millis(200), socket.next()).await;
        let text = match next {
            Err(_) => continue,
            Ok(Some(Ok(Message::Text(text)))) => text,
            Ok(Some(Ok(_))) => continue,
            Ok(_) => break,
        };
        if !text.as_str().starts_with(r#"{"type":"perception""#) {
            continue;
        }
        let arrived = Instant::now();
        let Some(tick) = number_after(text.as_bytes(), br#""tick":"#) else {
            continue;
        };
        if !think.is_zero() {
            tokio::time::sleep(think).await;
        }
        let command = format!(r#"{{"type":"command","tick":{tick},"action":{{"kind":"stand"}}}}"#);
        if socket.send(Message::Text(command.into())).await.is_err() {
            break;
        }
        let sent = Instant::now();
        if measuring.load(Ordering::Relaxed) {
            if let Some(at) = answered_at {
                seen.waits_us.push((arrived - at).as_micros() as u64);
            }
            seen.arrived.push((tick, arrived));
            seen.answered.push((tick, sent));
            seen.commands += 1;
            seen.first_tick.get_or_insert(tick);
            seen.last_tick = tick;
        }
        answered_at = Some(sent);
    }
    let _ = socket.close(None).await;
    Some(seen)
}

pub fn table(r: &BotRound) -> String {
    let watched = r.spectators.as_ref().map_or(String::new(), |s| {
        format!(
            "spectators of the same matches, same window (server CPU and RSS are both loads'):\n{}",
            super::table(std::slice::from_ref(s))
        )
    });
    let bots = format!(
        "{} in {} ({} connected), thinking {:.0} ms, {:.0} s window\n\
         ticks per match per second (median): {:.0}\n\
         tick turnaround (a match's last command sent -> its next perception) p50/p99/max: {:.2}/{:.2}/{:.2} ms\n\
         a bot's wait (its command sent -> its next perception) p50/p99/max: {:.2}/{:.2}/{:.2} ms\n\
         commands: {}; server CPU {:.2} s ({:.1} µs per command); server RSS {:.1} MB; load generator CPU {:.2} s\n",
        plural(r.bots as u64, "bot"),
        plural(r.matches as u64, "lock-step match"),
        r.connected,
        r.think_ms,
        r.window_s,
        r.ticks_per_s_median,
        r.turnaround_ms.p50,
        r.turnaround_ms.p99,
        r.turnaround_ms.max,
        r.bot_wait_ms.p50,
        r.bot_wait_ms.p99,
        r.bot_wait_ms.max,
        r.commands,
        r.server_cpu_s,
        r.server_cpu_us_per_command,
        r.server_rss_mb,
        r.loadgen_cpu_s
    );
    bots + &watched
}
