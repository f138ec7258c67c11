//! Prometheus metrics, kept as atomics and rendered in the text exposition format on
//! `GET /metrics`. A handful of counters does not need a metrics framework.

use std::fmt::Write;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Upper bounds of the tick-duration histogram, seconds.
const TICK_BUCKETS_S: [f64; 10] = [
    0.000_05, 0.000_1, 0.000_25, 0.000_5, 0.001, 0.002_5, 0.005, 0.01, 0.025, 0.05,
];

/// The server's counters, shared by every task and bumped without locks; `/metrics`
/// renders them for Prometheus.
#[derive(Default)]
pub struct Metrics {
    /// Ticks simulated, all matches.
    pub ticks: AtomicU64,
    /// Ticks that started more than a tick period late.
    pub tick_overruns: AtomicU64,
    tick_buckets: [AtomicU64; TICK_BUCKETS_S.len()],
    tick_count: AtomicU64,
    tick_sum_ns: AtomicU64,
    /// Matches created, demos included.
    pub matches_created: AtomicU64,
    /// Matches running now (a gauge).
    pub matches_running: AtomicU64,
    /// Match tasks that panicked (each ended its match with reason `error`).
    pub match_panics: AtomicU64,
    /// Spectator sockets open now (a gauge).
    pub spectators: AtomicU64,
    /// Bot sockets open now (a gauge).
    pub bots: AtomicU64,
    /// Frames written to spectators.
    pub frames_sent: AtomicU64,
    /// Frames a slow spectator skipped (it got a newer one).
    pub frames_dropped: AtomicU64,
    /// Bytes of WebSocket messages written.
    pub bytes_out: AtomicU64,
    /// Error messages sent to clients about their input.
    pub client_errors: AtomicU64,
    /// Sockets closed for an oversized message (1009).
    pub closed_for_size: AtomicU64,
    /// Sockets closed for flooding (1008).
    pub closed_for_rate: AtomicU64,
    /// Sockets closed for breaking the WebSocket protocol (1002) or sending text that is
    /// not UTF-8 (1007).
    pub closed_for_protocol: AtomicU64,
    /// Clients dropped for not reading within the send timeout.
    pub slow_clients_dropped: AtomicU64,
    /// Replay files that could not be written (the matches went on).
    pub replay_errors: AtomicU64,
    /// Replay files deleted by retention.
    pub replays_deleted: AtomicU64,
    /// Retention sweeps of the replay directory run.
    pub replay_sweeps: AtomicU64,
    /// WebSocket requests refused for their origin.
    pub refused_origin: AtomicU64,
    /// Connections refused at accept: their address had its share.
    pub refused_per_ip: AtomicU64,
    /// Connections refused at accept: every place was taken.
    pub refused_full: AtomicU64,
    /// WebSocket requests refused before the upgrade: no room for another socket of
    /// their kind.
    pub refused_busy: AtomicU64,
    /// Failures to accept a connection (descriptors or memory ran out).
    pub accept_errors: AtomicU64,
    /// REST requests answered 503 because too many were in flight.
    pub overloaded: AtomicU64,
}

impl Metrics {
    /// Counts a tick that took `seconds` to simulate, in the tick-time histogram.
    pub fn observe_tick(&self, seconds: f64) {
        self.ticks.fetch_add(1, Relaxed);
        self.tick_count.fetch_add(1, Relaxed);
        self.tick_sum_ns.fetch_add((seconds * 1e9) as u64, Relaxed);
        if let Some(k) = TICK_BUCKETS_S.iter().position(|&b| seconds <= b) {
            self.tick_buckets[k].fetch_add(1, Relaxed);
        }
    }

    /// Every counter in Prometheus' text exposition format.
    pub fn render(&self) -> String {
        let mut out = String::new();
        let mut counter = |name: &str, help: &str, kind: &str, value: u64| {
            let _ = writeln!(
                out,
                "# HELP {name} {help}\n# TYPE {name} {kind}\n{name} {value}"
            );
        };
        counter(
            "fieldhouse_ticks_total",
            "Ticks simulated, all matches.",
            "counter",
            self.ticks.load(Relaxed),
        );
        counter(
            "fieldhouse_tick_overruns_total",
            "Ticks that started more than a tick period late.",
            "counter",
            self.tick_overruns.load(Relaxed),
        );
        counter(
            "fieldhouse_matches_created_total",
            "Matches created, demos included.",
            "counter",
            self.matches_created.load(Relaxed),
        );
        counter(
            "fieldhouse_matches",
            "Matches running.",
            "gauge",
            self.matches_running.load(Relaxed),
        );
        counter(
            "fieldhouse_match_panics_total",
            "Matches ended with reason error: their task panicked (a bug; see the log).",
            "counter",
            self.match_panics.load(Relaxed),
        );
        counter(
            "fieldhouse_frames_sent_total",
            "Frames written to spectators.",
            "counter",
            self.frames_sent.load(Relaxed),
        );
        counter(
            "fieldhouse_frames_dropped_total",
            "Frames a slow spectator skipped (it got a newer one).",
            "counter",
            self.frames_dropped.load(Relaxed),
        );
        counter(
            "fieldhouse_bytes_out_total",
            "Bytes of WebSocket messages written.",
            "counter",
            self.bytes_out.load(Relaxed),
        );
        counter(
            "fieldhouse_client_errors_total",
            "Error messages sent to clients about their input.",
            "counter",
            self.client_errors.load(Relaxed),
        );
        counter(
            "fieldhouse_closed_oversized_total",
            "Sockets closed for an oversized message (1009).",
            "counter",
            self.closed_for_size.load(Relaxed),
        );
        counter(
            "fieldhouse_closed_flooding_total",
            "Sockets closed for flooding (1008).",
            "counter",
            self.closed_for_rate.load(Relaxed),
        );
        counter(
            "fieldhouse_closed_protocol_error_total",
            "Sockets closed for a frame that breaks the WebSocket protocol (1002) or text that is not UTF-8 (1007).",
            "counter",
            self.closed_for_protocol.load(Relaxed),
        );
        counter(
            "fieldhouse_replay_errors_total",
            "Replay files that could not be written (the matches went on).",
            "counter",
            self.replay_errors.load(Relaxed),
        );
        counter(
            "fieldhouse_replays_deleted_total",
            "Replay files deleted by retention (replay_retention_bytes, replay_retention_days).",
            "counter",
            self.replays_deleted.load(Relaxed),
        );
        counter(
            "fieldhouse_replay_sweeps_total",
            "Retention sweeps of the replay directory (at start, every minute, and after recordings finish: at most one a second).",
            "counter",
            self.replay_sweeps.load(Relaxed),
        );
        counter(
            "fieldhouse_slow_clients_dropped_total",
            "Clients (spectators, bots, replay viewers) dropped for not reading within the send timeout.",
            "counter",
            self.slow_clients_dropped.load(Relaxed),
        );
        counter(
            "fieldhouse_accept_errors_total",
            "Failures to accept a connection (descriptors or memory ran out).",
            "counter",
            self.accept_errors.load(Relaxed),
        );
        counter(
            "fieldhouse_requests_shed_total",
            "REST requests answered 503 because too many were in flight.",
            "counter",
            self.overloaded.load(Relaxed),
        );
        let _ = writeln!(
            out,
            "# HELP fieldhouse_connections Open WebSocket connections by role.\n# TYPE fieldhouse_connections gauge\nfieldhouse_connections{{role=\"spectator\"}} {}\nfieldhouse_connections{{role=\"bot\"}} {}",
            self.spectators.load(Relaxed),
            self.bots.load(Relaxed)
        );
        let _ = writeln!(
            out,
            "# HELP fieldhouse_sockets_refused_total Connections refused at accept (per_ip, full) and WebSocket requests refused before the upgrade (origin, busy), by reason.\n# TYPE fieldhouse_sockets_refused_total counter"
        );
        for (reason, counter) in [
            ("origin", &self.refused_origin),
            ("per_ip", &self.refused_per_ip),
            ("full", &self.refused_full),
            ("busy", &self.refused_busy),
        ] {
            let _ = writeln!(
                out,
                "fieldhouse_sockets_refused_total{{reason=\"{reason}\"}} {}",
                counter.load(Relaxed)
            );
        }
        let _ = writeln!(out, "# HELP fieldhouse_tick_duration_seconds Time to simulate one tick.\n# TYPE fieldhouse_tick_duration_seconds histogram");
        let mut cumulative = 0;
        for (bound, bucket) in TICK_BUCKETS_S.iter().zip(&self.tick_buckets) {
            cumulative += bucket.load(Relaxed);
            let _ = writeln!(
                out,
                "fieldhouse_tick_duration_seconds_bucket{{le=\"{bound}\"}} {cumulative}"
            );
        }
        let count = self.tick_count.load(Relaxed);
        let _ = writeln!(
            out,
            "fieldhouse_tick_duration_seconds_bucket{{le=\"+Inf\"}} {count}\nfieldhouse_tick_duration_seconds_sum {}\nfieldhouse_tick_duration_seconds_count {count}",
            self.tick_sum_ns.load(Relaxed) as f64 / 1e9
        );
        out
    }
}
