//! The spectator page in a real headless browser: `tests/browser/spectator.mjs` starts the
//! real binary on a loopback port and drives Debian's chromium with playwright-core
//! through the lobby, a live match of each sport (the fielder's-eye panel, the cost-map
//! overlay), a replay (seek, pause, step, download), a phone-sized window and a server
//! restart, with no error in the browser console. Screenshots land in
//! `target/browser-artifacts/`.
//!
//! Needs `node`, `/usr/bin/chromium` (or `CHROMIUM`) and `npm ci` in `tests/browser`;
//! `scripts/prerequisites` (run by `scripts/test`) sees to them.

mod common;

/// The page's pure modules (optics, fits, interpolation) against analytic oracles, in
/// Node: `node --test tests/browser/modules.test.mjs`.
#[test]
fn page_modules_match_their_analytic_oracles() {
    let driver = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser");
    let out = Command::new("node")
        .args(["--test", "modules.test.mjs"])
        .current_dir(&driver)
        .output()
        .expect("node runs (is Node.js installed?)");
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

use std::path::Path;
use std::process::Command;

#[test]
fn spectator_page_in_chromium() {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let driver = here.join("tests/browser");
    assert!(
        driver.join("node_modules/playwright-core").is_dir(),
        "playwright-core is not installed: run `npm ci --prefix tests/browser` (scripts/prerequisites does)"
    );
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    assert!(
        Path::new(&chromium).exists(),
        "no browser at {chromium}: install Debian's chromium (scripts/prerequisites does) or set CHROMIUM"
    );
    let artifacts = here.join("target/browser-artifacts");
    let out = Command::new("node")
        .arg(driver.join("spectator.mjs"))
        .current_dir(&driver)
        .env("FIELDHOUSE_BIN", env!("CARGO_BIN_EXE_fieldhouse"))
        .env_remove("FIELDHOUSE_MOCAP_DIR")
        .env(
            "FIELDHOUSE_CACHE_DIR",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("server-cache"),
        )
        .env("ARTIFACTS", &artifacts)
        .env("CHROMIUM", &chromium)
        .output()
        .expect("node runs (is Node.js installed?)");
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{said}");
    assert!(out.status.success(), "the browser checks failed:\n{said}");
    for shot in ["lobby", "baseball", "cricket", "basketball", "replay"] {
        assert!(
            artifacts.join(format!("{shot}.png")).is_file(),
            "no screenshot {shot}.png"
        );
    }
}
