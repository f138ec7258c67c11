// The spectator page end to end: the real `fieldhouse serve` on a loopback port, Debian's
// chromium (headless) driven by playwright-core. Run by tests/browser.rs, which passes:
//   FIELDHOUSE_BIN       the binary (its embedded motion capture drives basketball)
//   FIELDHOUSE_CACHE_DIR cost-map cache shared with the other tests
//   ARTIFACTS            where screenshots go
//   CHROMIUM             the browser (default /usr/bin/chromium)
// Each check throws with what it saw; the process exits 1 on the first failure, and
// stops by itself within DEADLINE_MS whatever happens.
import { chromium } from "playwright-core";
import { mkdirSync, mkdtempSync, rmSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { env, freePort, startServer as startOn } from "./harness.mjs";

const DEADLINE_MS = 240_000;
const BIN = env("FIELDHOUSE_BIN");
const CACHE = env("FIELDHOUSE_CACHE_DIR");
const ARTIFACTS = env("ARTIFACTS");
const CHROMIUM = env("CHROMIUM", "/usr/bin/chromium");
// Screenshots of this run only: an old failure.png must not outlive its failure.
rmSync(ARTIFACTS, { recursive: true, force: true });
mkdirSync(ARTIFACTS, { recursive: true });

const deadline = setTimeout(() => { console.error(`FAIL: no result in ${DEADLINE_MS / 1000} s`); cleanup(); process.exit(1); }, DEADLINE_MS);
let server = null, browser = null, page = null;
const replayDir = mkdtempSync(join(tmpdir(), "fieldhouse-replays-"));

function cleanup() {
  server?.kill("SIGKILL");
  rmSync(replayDir, { recursive: true, force: true });
}

function check(ok, what) {
  if (!ok) throw new Error(what);
  passed(what);
}

/** Says a check passed whose failure would have thrown already (a wait that timed out). */
function passed(what) {
  console.log(`ok: ${what.split(":")[0]}`);
}

/** The server on `port`, with the test's motion cache and replay directory. */
function startServer(port) {
  return startOn(BIN, port, ["--cache-dir", CACHE, "--replay-dir", replayDir]);
}

/**
 * Replay files an attacker could leave in the replay directory: HTML in every string
 * the lobby shows (a `sport` holding an <img onerror> once ran script there), and
 * a file name that is HTML. Each payload sets `window.__xss` if it ever runs.
 */
const HOSTILE = {
  sport: `<img src=x onerror="window.__xss=1">`,
  name: `<script>window.__xss=2</script>evil`,
  caught: `<img src=x onerror="window.__xss=3">`,
  file: `<img src=x onerror=window.__xss=4>`,
};
function plantHostileReplays() {
  // A header that reads (its scenario is valid) but whose match strings are HTML.
  const header = { record: "header", format: 1, match: { id: "evil", name: HOSTILE.name, sport: HOSTILE.sport },
    scenario: { sport: "baseball" }, seed: 1, started_unix_ms: "<b>when</b>" };
  const footer = { record: "footer", reason: "finished", result: { caught: HOSTILE.caught, dropped: "<i>1</i>", balls: 2 } };
  writeFileSync(join(replayDir, "hostile.jsonl"), `${JSON.stringify(header)}\n${JSON.stringify(footer)}\n`);
  writeFileSync(join(replayDir, `${HOSTILE.file}.jsonl`), "not a header\n");
}

async function main() {
  plantHostileReplays();
  const port = await freePort();
  const base = `http://127.0.0.1:${port}`;
  server = await startServer(port);
  browser = await chromium.launch({
    executablePath: CHROMIUM,
    // Root in a container has no sandbox; the rest keeps chromium off the closed network.
    args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
      "--disable-component-update", "--disable-sync"],
  });
  console.log(`browser: chromium ${browser.version()}`);
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  // Every Content-Security-Policy violation the page causes, whatever the console says.
  await context.addInitScript(() => {
    window.__violations = [];
    document.addEventListener("securitypolicyviolation", (e) => window.__violations.push(`${e.violatedDirective} ${e.blockedURI}`));
  });
  page = await context.newPage();
  const errors = [];
  page.on("console", (m) => { if (m.type() === "error") errors.push(`console: ${m.text()}`); });
  page.on("pageerror", (e) => errors.push(`page: ${e.message}`));
  const shot = (name) => page.screenshot({ path: join(ARTIFACTS, `${name}.png`) });

  // The lobby lists the demo matches as links to their views, and the recorded replays.
  await page.goto(`${base}/`);
  for (const id of ["demo-baseball", "demo-cricket", "demo-basketball"]) {
    await page.locator(`#matches a[href="#/matches/${id}"]`).waitFor({ timeout: 10_000 });
  }
  passed("lobby: lists the three demo matches as links");
  await page.locator(`#replays a[href^="#/replays/demo-baseball-"]`).waitFor({ timeout: 10_000 });
  passed("lobby: lists the demo matches' replays");
  const scoreText = await page.locator(`#matches tr:has(a[href="#/matches/demo-basketball"])`).textContent();
  check(/pts in \d+ possessions/.test(scoreText), `lobby: shows the basketball score: ${scoreText}`);
  // The motion source is named for visitors without any path of the server's.
  const source = await page.locator("#source").textContent();
  check(/^motion: CMU motion capture, embedded: \d+ clips and their mirror images$/.test(source), `lobby: names the motion source without a path: ${source}`);
  // A match the server does not have: the page says so, and shows no empty field, 3-D
  // button or agent picker around the message.
  await page.goto(`${base}/#/matches/no-such-match`);
  await page.locator("#hud", { hasText: 'the server has no match "no-such-match"' }).waitFor({ timeout: 15_000 });
  const bare = await page.evaluate(() => ["field", "toggle3d", "agent", "log"].filter((id) => {
    const box = document.getElementById(id).getBoundingClientRect();
    return box.width > 0 && box.height > 0;
  }));
  check(bare.length === 0, `unknown match: only the message shows (visible besides it: ${bare.join(", ") || "nothing"})`);
  await page.goto(`${base}/#/`);
  await page.locator(`#matches a[href="#/matches/demo-basketball"]`).waitFor({ timeout: 10_000 });
  // Ended matches without a name (a learner's episodes) are counted, not listed; an
  // ended match with a name still is. (A fast match of a second of play ends at once.)
  const admin = { Authorization: "Bearer browser-test-admin-token" };
  const ended = [];
  for (const name of [undefined, undefined, "a named match"]) {
    const made = await page.request.post(`${base}/api/matches?record=false`, {
      headers: admin, data: { sport: "baseball", mode: "fast", duration_s: 1, ...(name ? { name } : {}) },
    });
    check(made.status() === 201, `lobby: a match that ends at once is created (${made.status()})`);
    ended.push((await made.json()).id);
  }
  await page.locator("#matches", { hasText: "and 2 ended matches without a name, not listed" }).waitFor({ timeout: 10_000 });
  await page.locator(`#matches a[href="#/matches/${ended[2]}"]`).waitFor({ timeout: 10_000 });
  check(await page.locator(`#matches a[href="#/matches/${ended[0]}"]`).count() === 0, "lobby: an ended match without a name is not listed");
  passed("lobby: ended matches without a name are counted, not listed");
  await shot("lobby");

  // Hostile replay files: every string shows as text, nothing runs, and the page's
  // Content-Security-Policy (which would block the script anyway) is never violated.
  const hostileRow = page.locator(`#replays tr:has(a[href="#/replays/hostile"])`);
  await hostileRow.waitFor({ timeout: 10_000 });
  const hostileText = await hostileRow.textContent();
  for (const [what, text] of [["sport", HOSTILE.sport], ["name", HOSTILE.name], ["score", HOSTILE.caught]]) {
    check(hostileText.includes(text), `xss: a replay's ${what} shows as text: ${hostileText}`);
  }
  const unreadable = await page.locator("#replays").textContent();
  // A file whose name is no replay id (letters, digits, - and _) is not a replay at all.
  check(!unreadable.includes("onerror=window.__xss=4"), `xss: a file named with HTML is not listed: ${unreadable}`);
  const xss = await page.evaluate(() => window.__xss);
  check(xss === undefined, `xss: no payload ran (window.__xss is ${xss})`);
  const lobbyViolations = await page.evaluate(() => window.__violations);
  check(lobbyViolations.length === 0, `csp: the lobby violates none of its policy:\n${lobbyViolations.join("\n")}`);
  const csp = response => response.headers()["content-security-policy"] ?? "";
  const policy = csp(await page.request.get(`${base}/`));
  check(policy.includes("script-src 'self'") && !policy.includes("unsafe-inline"), `csp: the page is served with a policy without inline script: ${policy}`);

  // A live match: the HUD's tick rises and the canvas changes.
  await page.click(`#matches a[href="#/matches/demo-baseball"]`);
  check(page.url().endsWith("#/matches/demo-baseball"), `live: the view has its own URL: ${page.url()}`);
  const tick = async () => Number(await page.locator("#hud-tick").textContent());
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });
  const state = await page.locator("#hud .state").getAttribute("data-state");
  check(state === "live", `live: the HUD says the connection is live: ${state}`);
  const t1 = await tick();
  const pixels1 = await page.locator("#field").screenshot();
  await page.waitForTimeout(1000);
  const t2 = await tick();
  const pixels2 = await page.locator("#field").screenshot();
  check(t2 > t1 + 30, `live: the HUD tick rises at 60 Hz (${t1} then ${t2} a second later)`);
  check(!pixels1.equals(pixels2), "live: the canvas changes between two screenshots");

  // The fielder's-eye panel once a ball is well in the air (the demo launches every
  // few seconds; a new launch starts the panel afresh, so every look is one poll).
  const eye = await until(async () => {
    const text = await page.locator("#eye-text").textContent();
    const ink = await inked(page, "eye"), side = await inked(page, "side");
    return /lf \(chapman\): tan ψ rises [\d.]+\/s, straightness R² [\d.]+/.test(text) && ink > 4000 && side > 1000 &&
      { text, ink, side };
  }, 30_000, "eye: the fielder's-eye panel explains tan ψ and both plots are drawn");
  passed(`eye: the fielder's-eye panel is drawn (${eye.ink} pixels inked) and explained: ${eye.text}`);
  // The README's picture: the ball in flight, the fielders converging on it.
  await shot("baseball-flight");
  await labelsApart(page, "baseball");
  // The flight ends caught or on the ground, and the panel and the log say which.
  const outcome = await until(async () => {
    const text = await page.locator("#eye-text").textContent();
    return /Caught by \w+|Landed [\d.]+ m from \w+/.exec(text)?.[0];
  }, 30_000, "eye: the end of the flight is marked");
  const logged = await page.locator("#log").textContent();
  check(/caught by \w+ at|landed at/.test(logged), `eye: the end of the flight is marked (${outcome}) and logged`);
  // The catch or miss is marked where the fielders stand: its label too stays apart.
  await labelsApart(page, "baseball, the flight's end marked");
  await shot("baseball");

  // Picking another fielder from the list re-labels the panel.
  await page.selectOption("#agent", "cf");
  await page.waitForFunction(() => document.getElementById("eye-text").textContent.includes("cf (lot-optical)"), null, { timeout: 5_000 });
  passed("eye: picking cf shows its view");

  // Reloading the URL comes back to the same view.
  await page.reload();
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });
  check((await page.locator("#title").textContent()).includes("chapman, lot-optical and predictive"), "live: a reload shows the same match");

  await page.goto(`${base}/#/matches/demo-cricket`);
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });
  await page.waitForTimeout(1500);
  await shot("cricket");
  await labelsApart(page, "cricket");

  // Basketball: the cost-map overlay and the decisions.
  await page.goto(`${base}/#/matches/demo-basketball`);
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });
  await page.waitForFunction(() => document.getElementById("costmap-text").textContent.includes("moves with"), null, { timeout: 10_000 });
  // The map arrives by its own request: poll until it is drawn.
  const overlay = await until(async () => {
    const shares = await page.evaluate(() => {
      // The floor is wood (red over green over blue) and the surround dark grey: the
      // overlay's greens and blues (squares two seconds away and more) appear nowhere
      // else but on the offense's small markers.
      const c = document.getElementById("field");
      const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
      let cool = 0, surround = 0;
      for (let i = 0; i < d.length; i += 4) {
        if (Math.max(d[i + 1], d[i + 2]) > d[i] + 30) cool++;
        if (Math.max(d[i], d[i + 1], d[i + 2]) < 60) surround++;
      }
      return { cool: cool / (c.width * c.height), surround: surround / (c.width * c.height) };
    });
    return shares.cool > 0.1 && shares;
  }, 10_000, "court: the cost-map overlay covers the court (green or blue pixels)");
  check(overlay.cool > 0.1, `court: the cost-map overlay covers the court (${(100 * overlay.cool).toFixed(1)} % of pixels green or blue)`);
  // The canvas has the court's shape: the dark surround is the lines' margin, not bands
  // beside a square court on a wide canvas.
  check(overlay.surround < 0.12, `court: the dark surround is a thin margin (${(100 * overlay.surround).toFixed(1)} % of the canvas)`);
  // The holder changes with passes: read the text in the same look that finds it.
  // A decision on a square names the model of the defender it counted on.
  const decision = await (await page.waitForFunction(() => {
    const text = document.getElementById("decision").textContent;
    // A decision to shoot from a square (not a pass when pressed, which has no C_o).
    return text.includes("safe square") && text.includes("model)") && /Co (beyond )?[\d.]+ s/.test(text) && text;
  }, null, { timeout: 30_000 })).jsonValue();
  check(/^o\d /.test(decision) && /safe square/.test(decision), `court: the ball holder's decision is explained: ${decision}`);
  check(/\((own|maps:[\w-]+|kinematic|isotropic|none) model\)/.test(decision) && /Co (beyond )?[\d.]+ s/.test(decision),
    `court: the decision names the defender model and gives C_o: ${decision}`);
  await shot("basketball");
  await labelsApart(page, "basketball");

  // A player a bot moves: the picker and the decision panel say the bot decides, not
  // the built-in rule. The bot (this script, over a real socket) orders o1 to move.
  const created = await page.request.post(`${base}/api/matches`, {
    headers: { Authorization: "Bearer browser-test-admin-token" },
    data: { sport: "basketball", name: "bot court", agents: [{ id: "o1", team: "offense", bot: true },
      { id: "o2", team: "offense", strategy: "costmap" }, { id: "d1", team: "defense", strategy: "defense" }] },
  });
  check(created.status() === 201, `bot: a basketball match with a bot seat is created (${created.status()})`);
  const { id: botMatch, bot_tokens: tokens } = await created.json();
  // The bot runs in a page of its own (Node 20's WebSocket needs a flag).
  const botPage = await context.newPage();
  await botPage.goto(`${base}/healthz`);
  await botPage.evaluate((url) => {
    const bot = new WebSocket(url);
    let orders = 0;
    bot.onmessage = (event) => {
      const msg = JSON.parse(event.data);
      // Every tenth perception, a move across the court and back: orders keep coming.
      if (msg.type === "perception" && orders++ % 10 === 0) {
        const target = orders % 20 === 1 ? [4, 3] : [8, -3];
        bot.send(JSON.stringify({ type: "command", tick: msg.tick, action: { kind: "move_to", target } }));
      }
    };
  }, `ws://127.0.0.1:${port}/ws/matches/${botMatch}/play?token=${tokens.o1}`);
  await page.goto(`${base}/#/matches/${botMatch}`);
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });
  await page.selectOption("#agent", "o1");
  const botNamed = await (await page.waitForFunction(() => {
    const option = document.querySelector('#agent option[value="o1"]').textContent;
    const text = document.getElementById("decision").textContent;
    return option === "o1 · bot" && /bot/.test(text) && { option, text };
  }, null, { timeout: 15_000 })).jsonValue();
  check(!/costmap/.test(botNamed.option) && /connected bot|its bot's order/.test(botNamed.text),
    `bot: the picker names o1 "${botNamed.option}" and the panel says who decides: ${botNamed.text}`);
  await shot("basketball-bot");
  await botPage.close();

  // A phone-sized window: everything fits the width, the labels too (ids only).
  await page.setViewportSize({ width: 390, height: 844 });
  await page.waitForTimeout(500);
  const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  check(overflow <= 0, `phone: no sideways scrolling (${overflow} px too wide)`);
  await labelsApart(page, "basketball on a phone");
  await shot("basketball-phone");
  // The lobby on a phone: its tables (long ids, the hostile replays' long strings)
  // become cards that wrap, not rows wider than the screen.
  await page.goto(`${base}/#/`);
  await page.locator(`#replays a[href^="#/replays/demo-baseball-"]`).first().waitFor({ timeout: 10_000 });
  const lobbyOverflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  check(lobbyOverflow <= 0, `phone: the lobby has no sideways scrolling (${lobbyOverflow} px too wide)`);
  // Its cards keep status and score apart, as the table's columns do.
  const card = await page.evaluate(() => {
    const score = document.querySelector('#matches a[href="#/matches/demo-baseball"]').closest("tr").children[3];
    return getComputedStyle(score, "::before").content;
  });
  check(card.includes("·"), `phone: a lobby card sets the score apart from the status (${card})`);
  await shot("lobby-phone");
  await page.setViewportSize({ width: 1280, height: 800 });
  // A replay on a phone (a touch screen, no hover): the controls are in view when it
  // opens, and no keyboard hint is shown to a device without a keyboard.
  const phone = await browser.newContext({ viewport: { width: 390, height: 844 }, hasTouch: true, isMobile: true });
  const phonePage = await phone.newPage();
  await phonePage.goto(`${base}/#/`);
  const phoneLink = phonePage.locator(`#replays a[href^="#/replays/demo-baseball-"]`).first();
  await phoneLink.waitFor({ timeout: 10_000 });
  await phoneLink.click();
  await phonePage.locator("#player").waitFor({ state: "visible", timeout: 10_000 });
  const onPhone = await phonePage.evaluate(() => ({
    height: window.innerHeight,
    controls: document.getElementById("player").getBoundingClientRect().bottom,
    hint: getComputedStyle(document.getElementById("keys")).display,
  }));
  check(onPhone.controls <= onPhone.height && onPhone.hint === "none",
    `phone: a replay's controls are in view (bottom at ${onPhone.controls} of ${onPhone.height} px) and the keyboard hint is hidden (${onPhone.hint})`);
  await phone.close();

  // A replay: opens, plays, seeks, pauses, steps one tick.
  await page.goto(`${base}/#/`);
  const link = page.locator(`#replays a[href^="#/replays/demo-baseball-"]`).first();
  await link.waitFor({ timeout: 10_000 });
  const replayHref = await link.getAttribute("href");
  await link.click();
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });
  // The controls appear with the replay's hello, which comes once the server has read
  // the file (a demo's replay grows the whole time the server runs).
  await page.locator("#player").waitFor({ state: "visible", timeout: 10_000 });
  passed("replay: the player controls show");
  // On a laptop's screen (1280×800) the controls and the keyboard hint are in view
  // when the replay opens, without scrolling.
  const fold = await page.evaluate(() => ({
    height: window.innerHeight,
    controls: document.getElementById("player").getBoundingClientRect().bottom,
    keys: document.getElementById("keys").getBoundingClientRect().bottom,
    scrolled: window.scrollY,
  }));
  check(fold.scrolled === 0 && fold.controls <= fold.height && fold.keys <= fold.height,
    `replay: the controls are above the fold at 1280×${fold.height} (their bottom at ${fold.controls} px, the hint's at ${fold.keys} px)`);
  const last = Number(await page.locator("#seek").getAttribute("max"));
  check(last > 300, `replay: the seek bar spans the recording (last tick ${last})`);
  const target = Math.floor(last / 2);
  await page.locator("#seek").evaluate((el, t) => { el.value = t; el.dispatchEvent(new Event("change")); }, target);
  await page.waitForFunction((t) => Math.abs(Number(document.getElementById("hud-tick")?.textContent) - t) < 40, target, { timeout: 5_000 });
  passed(`replay: seeking to tick ${target} shows that moment`);
  await page.click("#play");
  await page.waitForFunction(() => document.getElementById("hud-playback")?.textContent.startsWith("paused"), null, { timeout: 2_000 });
  // Frames the server sent before it read the pause are still arriving: paused, the
  // page shows the newest frame, so let them land before taking the tick.
  await page.waitForTimeout(300);
  const paused = await tick();
  await page.waitForTimeout(800);
  check(await tick() === paused, `replay: paused, the tick stays at ${paused}`);
  await page.keyboard.press("ArrowRight");
  await page.waitForFunction((t) => Number(document.getElementById("hud-tick")?.textContent) > t, paused, { timeout: 3_000 });
  const stepped = await tick();
  check(stepped - paused <= 2, `replay: → steps to the next frame (${paused} to ${stepped})`);
  await page.keyboard.press("+");
  await page.waitForFunction(() => document.getElementById("hud-playback")?.textContent.includes("2×"), null, { timeout: 2_000 });
  check(await page.locator("#speed").inputValue() === "2", "replay: + doubles the speed");
  // Space plays (at 2× now) and pauses again.
  const before = await tick();
  await page.keyboard.press(" ");
  await page.waitForFunction(() => document.getElementById("hud-playback")?.textContent.startsWith("playing"), null, { timeout: 2_000 });
  await page.waitForTimeout(2000);
  await page.keyboard.press(" ");
  await page.waitForFunction(() => document.getElementById("hud-playback")?.textContent.startsWith("paused"), null, { timeout: 2_000 });
  const after = await tick();
  check(after - before > 90, `replay: space plays at 2× and pauses (${before} to ${after} in about 2 s)`);
  // A seek into a ball's flight, paused: the panels show the flight so far (the seek
  // asks for a lead-in), not "waiting for a fly ball" while the ball is up.
  await page.keyboard.press(" ");
  const inFlight = await until(async () => {
    const text = await page.locator("#eye-text").textContent();
    return /tan ψ rises/.test(text) && !/Caught by|Landed/.test(text) && await tick();
  }, 30_000, "replay: a ball in flight while playing");
  await page.keyboard.press(" ");
  await page.keyboard.press("Home");
  await page.waitForFunction((t) => Number(document.getElementById("hud-tick")?.textContent) < t - 300, inFlight, { timeout: 5_000 });
  // The log starts again at a seek: at the replay's start it tells at most of the first
  // ball, nothing of the balls played before the seek.
  const balls = async () => [...(await page.locator("#log").textContent()).matchAll(/ball (\d+):/g)].map((m) => Number(m[1]));
  await page.waitForTimeout(500);
  const atStart = await balls();
  check(atStart.every((b) => b <= 1), `replay: after a seek to the start the log tells only of ball 1 (it has balls ${atStart.join(", ") || "none"})`);
  await page.locator("#seek").evaluate((el, t) => { el.value = t; el.dispatchEvent(new Event("change")); }, inFlight);
  await page.waitForFunction((t) => Math.abs(Number(document.getElementById("hud-tick")?.textContent) - t) <= 2, inFlight, { timeout: 5_000 });
  const afterSeek = await until(async () => {
    const text = await page.locator("#eye-text").textContent();
    const side = await inked(page, "side");
    return /tan ψ rises/.test(text) && side > 1000 && { text, side };
  }, 3_000, `replay: after a seek to tick ${inFlight}, mid-flight, the fielder's eye and the side view show the flight`);
  passed(`replay: after a seek into a flight the panels show it: ${afterSeek.text}`);
  // And the log holds what the lead-in brought, each event once: the page played this
  // flight before it went back to the start, and none of that is left (10 s of lead-in
  // spans at most three balls).
  const inLog = await balls();
  const lines = await page.locator("#log > div").allTextContents();
  check(inLog.length > 0 && Math.max(...inLog) - Math.min(...inLog) <= 2 && new Set(lines).size === lines.length,
    `replay: after a seek into a flight the log tells of its lead-in only, once (${lines.join(" | ")})`);
  await shot("replay-seek-in-flight");
  const download = await page.locator("#download").getAttribute("href");
  const file = await page.request.get(`${base}${download}`);
  // The demo's recording is format 2: zstd frames, named so.
  const zstd = [0x28, 0xb5, 0x2f, 0xfd];
  const served = file.ok() && (await file.body()).subarray(0, 4).every((b, k) => b === zstd[k]);
  const named = /filename="[^"]+\.jsonl\.zst"/.test(file.headers()["content-disposition"] ?? "");
  check(served && named, `replay: the download link serves the file (${download}) as .jsonl.zst`);
  await shot("replay");

  // The server goes away: the page says so and reconnects when it is back.
  await page.goto(`${base}/#/matches/demo-baseball`);
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });
  server.kill("SIGTERM");
  await page.waitForFunction(() => document.querySelector("#hud .state").dataset.state === "retrying", null, { timeout: 10_000 });
  passed("reconnect: the HUD shows the server gone");
  await shot("disconnected");
  // The page notices the close before the old process has let go of the port.
  const gone = Date.now();
  if (server.exitCode === null && server.signalCode === null) await new Promise((r) => server.once("exit", r));
  console.log(`reconnect: the old server exited ${Date.now() - gone} ms after the page saw it go`);
  server = await startServer(port);
  await page.waitForFunction(() => document.querySelector("#hud .state").dataset.state === "live", null, { timeout: 20_000 });
  passed("reconnect: the page reconnects by itself when the server is back");

  // A replay link still works after the restart (same replay directory).
  await page.goto(`${base}/${replayHref}`);
  await page.locator("#hud-tick").waitFor({ timeout: 10_000 });

  // A hello of another protocol version (an old page left open across an upgrade) is
  // refused with a message that says what to do, and the page stops there.
  const other = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  await other.addInitScript(() => {
    const slot = Object.getOwnPropertyDescriptor(WebSocket.prototype, "onmessage");
    Object.defineProperty(WebSocket.prototype, "onmessage", {
      get: slot.get,
      set(handler) {
        slot.set.call(this, (event) => {
          const msg = JSON.parse(event.data);
          if (msg.type === "hello") msg.version = 99;
          handler(new MessageEvent("message", { data: JSON.stringify(msg) }));
        });
      },
    });
  });
  const newer = await other.newPage();
  await newer.goto(`${base}/#/matches/demo-baseball`);
  await newer.locator("#mismatch").waitFor({ state: "visible", timeout: 10_000 });
  const mismatch = await newer.locator("#mismatch").textContent();
  check(/version 3/.test(mismatch) && /version 99/.test(mismatch) && /Reload/.test(mismatch),
    `version: a hello of version 99 is refused with a message: ${mismatch}`);
  check(await newer.locator("#hud-tick").count() === 0, "version: no frame is drawn after a refused hello");
  await newer.screenshot({ path: join(ARTIFACTS, "version-mismatch.png") });
  await other.close();

  // Connection failures while the server was down are expected; nothing else may be.
  const unexpected = errors.filter((e) => !/WebSocket connection to .* failed|ERR_CONNECTION_REFUSED/.test(e));
  check(unexpected.length === 0, `console: no errors:\n${unexpected.join("\n")}`);
  const violations = await page.evaluate(() => window.__violations);
  check(violations.length === 0, `csp: the page's own code violates none of its policy:\n${violations.join("\n")}`);
}

/** Polls `look` every 200 ms until it returns something truthy; fails after `ms`. */
async function until(look, ms, what) {
  const end = Date.now() + ms;
  for (;;) {
    const seen = await look();
    if (seen) return seen;
    if (Date.now() > end) throw new Error(`${what}: not within ${ms / 1000} s`);
    await new Promise((r) => setTimeout(r, 200));
  }
}

/**
 * Looks at the field's labels ten times over two seconds: no label may overlap another,
 * a marker or the ball (the boxes the page placed, in CSS pixels), and every agent the
 * picker lists must be named each time.
 */
async function labelsApart(page, what) {
  const agents = await page.evaluate(() => [...document.querySelectorAll("#agent option")].map((o) => o.value).filter((v) => !v.startsWith("@")));
  let worst = null, fewest = Infinity;
  for (let look = 0; look < 10; look++) {
    const seen = await page.evaluate(() => {
      const c = document.getElementById("field");
      const boxes = c.placedLabels ?? [], things = c.labelObstacles ?? [];
      const hit = (a, b) => a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
      const clashes = [];
      boxes.forEach((a, i) => {
        boxes.slice(i + 1).forEach((b) => { if (hit(a, b)) clashes.push(`"${a.text}" over "${b.text}"`); });
        things.forEach((b) => { if (hit(a, b)) clashes.push(`"${a.text}" over a marker or the ball`); });
      });
      return { count: boxes.length, clashes, texts: boxes.map((b) => b.text) };
    });
    if (seen.clashes.length && !worst) worst = seen;
    fewest = Math.min(fewest, agents.filter((id) => seen.texts.some((t) => t === id || t.startsWith(`${id} `))).length);
    await new Promise((r) => setTimeout(r, 200));
  }
  check(!worst, `labels (${what}): none overlaps another or a marker: ${worst?.clashes.join("; ")}`);
  check(fewest === agents.length, `labels (${what}): all ${agents.length} agents named at every look (fewest ${fewest})`);
}

/** How many pixels of a canvas are not blank. */
function inked(page, id) {
  return page.evaluate((id) => {
    const c = document.getElementById(id);
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++;
    return n;
  }, id);
}

try {
  await main();
  console.log(`all checks passed; screenshots in ${ARTIFACTS}`);
} catch (e) {
  console.error(`FAIL: ${e.message}`);
  await page?.screenshot({ path: join(ARTIFACTS, "failure.png") }).catch(() => {});
  console.error(`the page at the failure: ${join(ARTIFACTS, "failure.png")}`);
  process.exitCode = 1;
} finally {
  await browser?.close();
  cleanup();
  clearTimeout(deadline);
}
