// One match or replay on screen: the socket (stream.js), the frames and the clock that
// interpolates them (timeline.js), the sport's drawing (fly.js or court.js), the HUD,
// the event log, the agent picker, and for replays the player (player.js).
import { $, clock, escapeHtml, formatScore } from "./draw.js";
import { CourtView } from "./court.js";
import { FlyView } from "./fly.js";
import { Player } from "./player.js";
import { Stream } from "./stream.js";
import { Timeline } from "./timeline.js";
import { View3d } from "./view3d.js";

const LOG_LINES = 300;
/**
 * The protocol this page speaks (PROTOCOL.md). The page and the server ship together,
 * but a browser can keep an old page open (or cached) across a server upgrade: a hello
 * of another protocol or version is refused with a message, never half-understood.
 */
export const PROTOCOL = { name: "fieldhouse", versions: [3] };
/** The agent picker's choice that follows whoever has the ball. */
const FOLLOW_BALL = "@ball";

/** Shows `/#/{kind}/{id}` (kind `matches` or `replays`); returns what closes it. */
export function showView(kind, id) {
  $("lobby").hidden = true;
  $("view").hidden = false;
  $("title").textContent = id;
  $("log").replaceChildren();
  $("player").hidden = true;
  $("mismatch").hidden = true;
  $("picture").hidden = true;
  document.title = `${id} · fieldhouse`;

  const replay = kind === "replays";
  const timeline = new Timeline();
  let hello = null, sport = null, player = null, selected = null, ended = null, holder = null;
  let connection = { state: "connecting", detail: "" };
  let shownHud = "";
  let shown = null;
  // The 3-D view, while it is toggled on (view3d.js).
  let three = null;
  const toggle3d = () => {
    three?.dispose();
    three = three || !hello ? null : new View3d($("view3d"), hello);
    $("view3d").hidden = !three;
    $("field").hidden = Boolean(three);
    $("toggle3d").textContent = three ? "2-D view" : "3-D view";
  };
  $("toggle3d").addEventListener("click", toggle3d);

  const onHello = (msg) => {
    if (msg.protocol !== PROTOCOL.name || !PROTOCOL.versions.includes(msg.version)) {
      stream.close();
      const spoken = `${escapeHtml(msg.protocol)} version ${escapeHtml(msg.version)}`;
      $("mismatch").innerHTML = `This page speaks ${PROTOCOL.name} protocol version ${PROTOCOL.versions.join(" or ")}; ` +
        `the server speaks ${spoken}. Reload the page to get the server's own page` +
        ` (if it persists, the server and this page come from different releases).`;
      $("mismatch").hidden = false;
      connection = { state: "gone", detail: "protocol mismatch" };
      return;
    }
    hello = msg;
    $("picture").hidden = false;
    timeline.clear();
    shown = null;
    ended = null;
    const basketball = msg.match.field.kind === "basketball";
    sport = basketball ? new CourtView(msg) : new FlyView(msg);
    // The field's canvas takes the shape of the ground it shows (no dark bands beside a
    // square court), no taller than most of the window.
    const [x0, x1, z0, z1] = sport.frame.bounds, aspect = (x1 - x0) / (z1 - z0);
    Object.assign($("field").style, { aspectRatio: `${aspect}`, maxWidth: `calc(78vh * ${aspect})` });
    if (three) { three.dispose(); three = new View3d($("view3d"), msg); }
    $("title").textContent = `${msg.match.name || msg.match.id} · ${msg.match.sport}${replay ? " (replay)" : ""}`;
    $("source").textContent = `motion: ${msg.match.motion_source}`;
    $("fly-panels").hidden = basketball;
    $("court-panels").hidden = !basketball;
    const picker = $("agent");
    // In basketball the story follows the ball: by default the panels show whoever
    // holds it (or last held it).
    picker.innerHTML = (basketball ? `<option value="${FOLLOW_BALL}">the ball holder</option>` : "") +
      msg.match.agents
        .map((a) => `<option value="${escapeHtml(a.id)}">${escapeHtml(a.id)} · ${escapeHtml(a.strategy)}</option>`)
        .join("");
    const choices = [...picker.options].map((o) => o.value);
    if (!choices.includes(selected)) selected = choices[0] ?? null;
    picker.value = selected;
    holder = null;
    bots = null;
    if (replay) {
      player?.close();
      const ticksPerFrame = Math.max(1, Math.round(msg.match.tick_hz / msg.match.frame_hz));
      player = new Player(msg.replay, ticksPerFrame, {
        send: (control) => stream.send(control),
        onSeek: () => { timeline.clear(); sport.reset(); clearLog(); },
        leadInS: sport.leadInS,
        tickHz: msg.match.tick_hz,
      });
    }
  };

  const stream = new Stream(`/ws/${kind}/${encodeURIComponent(id)}`, {
    endIsFinal: !replay,
    onMessage: (msg) => {
      if (msg.type === "hello") onHello(msg);
      else if (msg.type === "frame" && hello) {
        // A frame from before the newest starts the story again (a seek's lead-in after
        // frames that were on their way): the view forgets what it gathered too.
        if (timeline.newest && msg.tick <= timeline.newest.tick) { sport.reset(); clearLog(); }
        timeline.push(msg);
        player?.frame(msg.tick);
      }
      else if (msg.type === "end") {
        ended = msg;
        player?.ended();
        log(`end: ${msg.reason}${msg.result ? `; ${formatScore(hello?.match.sport, msg.result)}` : ""}`, "end");
      } else if (msg.type === "error") log(`server: ${msg.code}: ${msg.message}`, "error");
    },
    onState: (s) => {
      connection = s;
      // A live match the server no longer has will not come back: say so and stop.
      if (s.state === "retrying" && !replay) {
        // Asked of the list, which answers 200 either way: a 404 would be an error in
        // the console of a page that did nothing wrong.
        fetch("/api/matches").then((r) => (r.ok ? r.json() : null)).then((list) => {
          if (list && !list.matches.some((m) => m.id === id)) {
            stream.close();
            connection = { state: "gone", detail: `the server has no match "${id}"` };
          }
        }, () => {});
      }
    },
  });

  const onPick = () => { selected = $("agent").value; };
  const onClick = (e) => {
    const rect = $("field").getBoundingClientRect();
    const picked = sport?.pick(e.clientX - rect.left, e.clientY - rect.top, timeline.sample());
    if (picked) { selected = picked; $("agent").value = picked; }
  };
  $("agent").addEventListener("change", onPick);
  $("field").addEventListener("click", onClick);

  let last = performance.now(), frameId = 0;
  const draw = (now) => {
    const dt = Math.min(0.25, (now - last) / 1000);
    last = now;
    if (hello && sport) {
      // Live: real time, a little behind the newest frame. A replay plays at its speed;
      // paused, it shows the frame it stopped on.
      const playing = !player || player.playing;
      const due = timeline.advance(dt, playing ? (player?.speed ?? 1) : 0, playing ? undefined : 0);
      for (const frame of due) {
        sport.apply(frame);
        // After a seek the log tells what the lead-in delivers, and nothing older.
        if (player?.stale(frame.tick)) continue;
        for (const e of frame.events) {
          const text = sport.describe(e);
          if (text) log(text, e.kind);
        }
      }
      // Between a seek and the frame it brings, the last picture stays up.
      const sample = (shown = timeline.sample() ?? shown);
      if (sample) {
        namePickedAgents(sample);
        holder = sample.ball.holder ?? holder ?? sample.agents[0]?.id;
        const agent = selected === FOLLOW_BALL ? holder : selected;
        if (three) three.draw(sample, agent, sport.flight);
        else sport.draw($("field"), sample, agent);
        sport.drawPanels(sample, agent);
      }
      hud(sample);
    } else hud(null);
    frameId = requestAnimationFrame(draw);
  };
  frameId = requestAnimationFrame(draw);

  /**
   * The picker names each agent by what moves it now: its built-in strategy, or "bot"
   * while a connected bot does (frames say so; the hello only knows the strategy).
   */
  let bots = null;
  function namePickedAgents(sample) {
    const now = sample.agents.filter((a) => a.controller === "bot").map((a) => a.id).join(" ");
    if (now === bots) return;
    bots = now;
    const byBot = new Set(now.split(" "));
    for (const option of $("agent").options) {
      const agent = hello.match.agents.find((a) => a.id === option.value);
      if (agent) option.textContent = `${agent.id} · ${byBot.has(agent.id) ? "bot" : agent.strategy}`;
    }
  }

  function hud(sample) {
    const words = {
      connecting: ["state-wait", "connecting"],
      live: ["state-live", replay ? "connected" : "live"],
      ended: ["state-gone", "ended"],
      retrying: ["state-gone", "disconnected"],
      gone: ["state-gone", "gone"],
    }[connection.state];
    const state = ended && connection.state === "live" ? ["state-gone", replay ? "at the end" : "ended"] : words;
    const parts = [`<span class="state ${state[0]}" data-state="${connection.state}">${state[1]}</span>`];
    if (connection.detail) parts.push(`<span>${escapeHtml(connection.detail)}</span>`);
    if (sample) {
      // Numbers are coerced: a replay's frames are whatever its file holds.
      parts.push(`<span>tick <b id="hud-tick">${Number(sample.tick)}</b></span>`, `<span>${clock(Number(sample.time_s))}</span>`);
      parts.push(`<span>${escapeHtml(formatScore(hello.match.sport, sample.score))}</span>`);
      if (sample.score.shot_clock_s !== undefined) parts.push(`<span>shot clock ${Number(sample.score.shot_clock_s).toFixed(1)}</span>`);
    }
    if (player) parts.push(`<span id="hud-playback">${player.status()}</span>`);
    if (ended) parts.push(`<span>${escapeHtml(ended.reason)}</span>`);
    const html = parts.join("");
    if (html !== shownHud) $("hud").innerHTML = shownHud = html;
  }

  function clearLog() {
    $("log").replaceChildren();
  }

  function log(text, kind) {
    const line = document.createElement("div");
    line.className = kind;
    line.textContent = text;
    const box = $("log");
    box.prepend(line);
    while (box.childElementCount > LOG_LINES) box.lastChild.remove();
  }

  return () => {
    cancelAnimationFrame(frameId);
    stream.close();
    player?.close();
    $("agent").removeEventListener("change", onPick);
    $("field").removeEventListener("click", onClick);
    $("toggle3d").removeEventListener("click", toggle3d);
    if (three) toggle3d();
  };
}
