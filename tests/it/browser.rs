//! The spectator page in a real headless browser: `tests/browser/spectator.mjs` starts the
//! real binary on a loopback port and drives Debian's chromium with playwright-core
//! through the lobby, a live match of each sport (the fielder's-eye panel, the cost-map
//! overlay), a replay (seek, pause, step, download), a phone-sized window and a server
//! restart, with no error in the browser console; `tests/browser/view3d.mjs` checks the
//! 3-D view. Screenshots land in `target/browser-artifacts/` (and `-3d/`).
//!
//! Needs `node`, `/usr/bin/chromium` (or `CHROMIUM`) and `npm ci` in `tests/browser`;
//! `scripts/prerequisites` (run by `scripts/test`) sees to them.

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

/// Runs the browser script `script` of `tests/browser` against the real binary, its
/// screenshots into `artifacts`; fails with all it said if it fails.
fn run_in_chromium(script: &str, artifacts: &Path) {
    let driver = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser");
    assert!(
        driver.join("node_modules/playwright-core").is_dir(),
        "playwright-core is not installed: run `npm ci --prefix tests/browser` (scripts/prerequisites does)"
    );
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    assert!(
        Path::new(&chromium).exists(),
        "no browser at {chromium}: install Debian's chromium (scripts/prerequisites does) or set CHROMIUM"
    );
    let out = Command::new("node")
        .arg(driver.join(script))
        .current_dir(&driver)
        .env("FIELDHOUSE_BIN", env!("CARGO_BIN_EXE_fieldhouse"))
        .env_remove("FIELDHOUSE_MOCAP_DIR")
        .env(
            "FIELDHOUSE_CACHE_DIR",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("server-cache"),
        )
        .env("ARTIFACTS", artifacts)
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
}

#[test]
fn spectator_page_in_chromium() {
    let artifacts = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/browser-artifacts");
    run_in_chromium("spectator.mjs", &artifacts);
    for shot in ["lobby", "baseball", "cricket", "basketball", "replay"] {
        assert!(
            artifacts.join(format!("{shot}.png")).is_file(),
            "no screenshot {shot}.png"
        );
    }
}

/// The 3-D view (`tests/browser/view3d.mjs`): basketball skeletons posed exactly from the
/// served poses for the frame shown (node and blend of a frame the script receives
/// itself), the follow camera, and a fielder's eye that sees a fly ball rise with tan ψ.
/// Its own artifacts directory: the spectator script empties its own when it starts.
#[test]
fn view3d_in_chromium() {
    let artifacts = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/browser-artifacts-3d");
    run_in_chromium("view3d.mjs", &artifacts);
    for shot in [
        "view3d-basketball",
        "view3d-basketball-follow",
        "view3d-fielders-eye",
    ] {
        assert!(
            artifacts.join(format!("{shot}.png")).is_file(),
            "no screenshot {shot}.png"
        );
    }
}
