//! Running the real `fieldhouse` binary from integration tests.

// Each test binary uses the part of this it needs.
#![allow(dead_code)]

pub mod server;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the binary with a command line written as one string (no argument has spaces),
/// without ambient motion, cache or log settings, so each test says what it uses.
pub fn fieldhouse(command_line: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(command_line.split_whitespace())
        .env_remove("FIELDHOUSE_MOCAP_DIR")
        .env_remove("FIELDHOUSE_CACHE_DIR")
        .env_remove("FIELDHOUSE_LOG")
        .output()
        .expect("the binary runs")
}

/// Runs a command that must succeed and print exactly one JSON document.
pub fn json(command_line: &str) -> Value {
    let out = fieldhouse(command_line);
    assert!(
        out.status.success(),
        "{command_line} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is exactly one JSON document")
}

/// Runs a command that must fail without printing to stdout; returns its stderr.
pub fn failure(command_line: &str) -> String {
    let out = fieldhouse(command_line);
    assert!(!out.status.success(), "{command_line} succeeded");
    assert!(out.stdout.is_empty(), "{command_line} printed to stdout");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The repository's copy of the CMU motion capture (the files the binary embeds), for
/// tests of `--mocap DIR`. Every other test runs on the embedded default, as users do.
pub fn repository_mocap() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/mocap")
}
