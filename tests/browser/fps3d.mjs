// Measures the 3-D view's frame rate: the basketball demo in headless chromium (software
// WebGL, as on a machine without a GPU), requestAnimationFrame callbacks and 3-D renders
// counted over SECONDS (10 by default) after a few seconds of warm-up. Not a test: a
// figure for BENCHMARKS.md.
//   FIELDHOUSE_BIN=target/release/fieldhouse node tests/browser/fps3d.mjs
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { env, freePort, launch, startServer } from "./harness.mjs";

const SECONDS = Number(env("SECONDS", "10"));
const cache = mkdtempSync(join(tmpdir(), "fieldhouse-fps-"));
const port = await freePort();
const server = await startServer(env("FIELDHOUSE_BIN"), port, ["--cache-dir", env("FIELDHOUSE_CACHE_DIR", cache)]);
const browser = await launch(env("CHROMIUM", "/usr/bin/chromium"));
try {
  const page = await (await browser.newContext({ viewport: { width: 1280, height: 900 } })).newPage();
  await page.goto(`http://127.0.0.1:${port}/#/matches/demo-basketball`);
  await page.locator("#toggle3d").click();
  await page.waitForFunction(() => window.fieldhouse3d?.agents.length === 3, null, { timeout: 30_000 });
  await page.waitForTimeout(3000);
  const got = await page.evaluate((seconds) => new Promise((resolve) => {
    let callbacks = 0;
    const renders = window.fieldhouse3d.renders, start = performance.now();
    const count = (now) => {
      callbacks++;
      if (now - start < seconds * 1000) requestAnimationFrame(count);
      else resolve({ callbacks, renders: window.fieldhouse3d.renders - renders, seconds: (now - start) / 1000, canvas: document.querySelector("#view3d canvas").width });
    };
    requestAnimationFrame(count);
  }), SECONDS);
  console.log(`3-D view, basketball demo, canvas ${got.canvas} px wide: ${(got.callbacks / got.seconds).toFixed(1)} animation frames/s, ` +
    `${(got.renders / got.seconds).toFixed(1)} 3-D renders/s over ${got.seconds.toFixed(1)} s`);
} finally {
  await browser.close();
  server.kill("SIGKILL");
  rmSync(cache, { recursive: true, force: true });
}
