//! Running the real `fieldhouse` binary from integration tests.

pub(crate) mod server;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// How often the waits below ask again.
const ASK_EVERY: Duration = Duration::from_millis(20);

/// What `found` finds, asked every 20 ms for at most `within`: None if it found nothing
/// in that time. For a wait whose failure should say what it saw last (the caller keeps
/// that); [`until`] is the usual wait.
pub(crate) async fn found_within<T>(
    within: Duration,
    mut found: impl FnMut() -> Option<T>,
) -> Option<T> {
    let deadline = Instant::now() + within;
    loop {
        if let Some(t) = found() {
            return Some(t);
        }
        if Instant::now() >= deadline {
            return None;
        }
        tokio::time::sleep(ASK_EVERY).await;
    }
}

/// Waits until `done`, asking every 20 ms; after `within`, panics with `what` (what
/// never happened). A wait on the condition, not a sleep that hopes it was long enough.
pub(crate) async fn until(within: Duration, what: &str, mut done: impl FnMut() -> bool) {
    if found_within(within, || done().then_some(()))
        .await
        .is_none()
    {
        panic!("{what} (waited {within:?})");
    }
}

/// [`until`] for a test that has no runtime of its own.
pub(crate) fn until_blocking(within: Duration, what: &str, done: impl FnMut() -> bool) {
    tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .build()
        .expect("a runtime for the wait")
        .block_on(until(within, what, done));
}

/// Runs the binary with a command line written as one string (no argument has spaces),
/// without ambient motion, cache or log settings, so each test says what it uses.
pub(crate) fn fieldhouse(command_line: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(command_line.split_whitespace())
        .env_remove("FIELDHOUSE_MOCAP_DIR")
        .env_remove("FIELDHOUSE_CACHE_DIR")
        .env_remove("FIELDHOUSE_LOG")
        .output()
        .expect("the binary runs")
}

/// Runs a command that must succeed; returns what it wrote to stdout and to stderr.
pub(crate) fn success(command_line: &str) -> (String, String) {
    exits(command_line, 0)
}

/// Runs a command that must end with exit code `code` (README, "Exit codes"); returns
/// what it wrote to stdout and to stderr.
pub(crate) fn exits(command_line: &str, code: i32) -> (String, String) {
    let out = fieldhouse(command_line);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "{command_line}: {stderr}");
    (
        String::from_utf8(out.stdout).expect("stdout is text"),
        stderr,
    )
}

/// Runs a command that must succeed and print exactly one JSON document.
pub(crate) fn json(command_line: &str) -> Value {
    serde_json::from_str(&success(command_line).0).expect("stdout is exactly one JSON document")
}

/// `fieldhouse replay verify FILE` must verify the whole file (exit code 0).
pub(crate) fn assert_verifies(file: &Path) {
    exits(&format!("replay verify {}", file.display()), 0);
}

/// `fieldhouse replay verify FILE` of a file cut at its end (a crash, a match still
/// recording) must verify its readable part: exit code 3.
pub(crate) fn assert_verifies_up_to_its_cut(file: &Path) {
    exits(&format!("replay verify {}", file.display()), 3);
}

/// Runs a command that must fail without printing to stdout; returns its stderr.
pub(crate) fn failure(command_line: &str) -> String {
    let out = fieldhouse(command_line);
    assert!(!out.status.success(), "{command_line} succeeded");
    assert!(out.stdout.is_empty(), "{command_line} printed to stdout");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `fieldhouse ARGS` refused for input wrong before anything ran (an argument, a
/// setting, a scenario file): exit code 2, nothing on stdout; its stderr.
pub(crate) fn bad_input(command_line: &str) -> String {
    let (stdout, stderr) = exits(command_line, 2);
    assert!(stdout.is_empty(), "{command_line} printed to stdout");
    stderr
}

/// The repository's copy of the CMU motion capture (the files the binary embeds), for
/// tests of `--mocap DIR`. Every other test runs on the embedded default, as users do.
pub(crate) fn repository_mocap() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/mocap")
}

/// Nouns the binary counts in its human-readable lines, in the plural.
const COUNTED: [&str; 18] = [
    "possessions",
    "passes",
    "launches",
    "balls",
    "frames",
    "ticks",
    "points",
    "entries",
    "matches",
    "bots",
    "commands",
    "squares",
    "spectators",
    "sessions",
    "failures",
    "clips",
    "cells",
    "walks",
];

/// Asserts that text meant for people rounds its figures (at most four decimals) and
/// counts in words ("1 possession", never "1 possessions").
pub(crate) fn assert_reads_well(text: &str) {
    for token in text.split(|c: char| !(c.is_ascii_digit() || c == '.')) {
        if let Some((whole, decimals)) = token.split_once('.') {
            let number = !whole.is_empty() && decimals.chars().all(|c| c.is_ascii_digit());
            assert!(
                !(number && decimals.len() > 4),
                "an unrounded figure, {token}, in:\n{text}"
            );
        }
    }
    let words: Vec<&str> = text.split_whitespace().collect();
    for pair in words.windows(2) {
        let count = pair[0].trim_start_matches('(');
        let noun = pair[1].trim_end_matches(|c: char| !c.is_alphabetic());
        assert!(
            !(count == "1" && COUNTED.contains(&noun)),
            "\"1 {noun}\" in:\n{text}"
        );
    }
}
