// The lobby: live matches and recorded replays, refreshed every two seconds. Entries
// are real links to their views' URLs.
import { $, escapeHtml, formatScore } from "./draw.js";

const REFRESH_MS = 2000;
// The replays shown: the listing's first page, the newest (a directory may hold
// thousands, and the server answers a page at a time).
const REPLAYS_SHOWN = 100;

export function showLobby() {
  $("lobby").hidden = false;
  $("view").hidden = true;
  document.title = "fieldhouse";
  let timer = null;
  let stopped = false;
  const load = async () => {
    try {
      const [live, recorded] = await Promise.all([getJson("/api/matches"), getJson(`/api/replays?limit=${REPLAYS_SHOWN}`)]);
      if (stopped) return;
      $("matches").innerHTML = live.matches.length
        ? matchRows(live.matches)
        : `<tr><td colspan="5" class="muted">no matches</td></tr>`;
      const recording = new Set(live.matches.filter((m) => m.status === "running").map((m) => m.replay));
      $("replays").innerHTML = recorded.replays.length
        ? recorded.replays.map((r) => replayRow(r, r.recording || recording.has(r.id))).join("") + moreRow(recorded)
        : `<tr><td colspan="5" class="muted">no replays (start the server with --replay-dir DIR to record matches)</td></tr>`;
      // Only basketball moves with motion capture; the lobby names it when one is on.
      const moving = live.matches.find((m) => m.sport === "basketball");
      $("source").textContent = moving ? `motion: ${moving.motion_source}` : "";
      $("lobby-state").textContent = `updated ${new Date().toLocaleTimeString()}`;
    } catch (e) {
      if (!stopped) $("lobby-state").textContent = `server unreachable (${e.message}); retrying…`;
    }
    if (!stopped) timer = setTimeout(load, REFRESH_MS);
  };
  load();
  return () => { stopped = true; clearTimeout(timer); };
}

async function getJson(path) {
  const response = await fetch(path, { cache: "no-store" });
  if (!response.ok) throw new Error(`${path}: HTTP ${response.status}`);
  return response.json();
}

/**
 * The matches running first, then the ended ones with a name; ended matches without one
 * (a learner's episodes, an evaluation's games: the server keeps ended matches listed
 * for a while so clients can read their results) are counted in a line, not listed.
 */
function matchRows(matches) {
  const running = matches.filter((m) => m.status === "running");
  const ended = matches.filter((m) => m.status !== "running");
  const named = ended.filter((m) => m.name);
  const unnamed = ended.length - named.length;
  const hidden = unnamed
    ? `<tr><td colspan="5" class="muted">and ${unnamed} ended ${unnamed === 1 ? "match" : "matches"} without a name, not listed</td></tr>`
    : "";
  return running.concat(named).map(matchRow).join("") + hidden;
}

// Every string from the server is escaped and every number coerced before it goes
// into the page: a replay file's header is whatever was written to the disk, and a
// `sport` holding HTML once ran script here.
function matchRow(m) {
  const name = escapeHtml(m.name || m.id);
  return `<tr><td><a href="#/matches/${encodeURIComponent(m.id)}">${name}</a></td>` +
    `<td>${escapeHtml(m.sport)}</td><td>${escapeHtml(m.status)}, tick ${Number(m.tick)}</td>` +
    `<td>${escapeHtml(formatScore(m.sport, m.score))}</td><td>${Number(m.spectators)}</td></tr>`;
}

/** A replay; `recording`: its match is still running and writing it. */
function replayRow(r, recording) {
  const file = `<a href="/api/replays/${encodeURIComponent(r.id)}" download>${size(Number(r.bytes))}</a>`;
  if (r.error) return `<tr><td>${escapeHtml(r.id)}</td><td></td><td>unreadable: ${escapeHtml(r.error)}</td><td></td><td>${file}</td></tr>`;
  // A never-ending match's replay comes in parts (segments), each a file.
  const part = r.segment ? ` (part ${Number(r.segment) + 1}, from tick ${Number(r.first_tick)})` : "";
  const name = escapeHtml((r.name || r.match || r.id) + part);
  const started = r.started_unix_ms
    ? ` <span class="muted">${escapeHtml(new Date(Number(r.started_unix_ms)).toLocaleString())}</span>`
    : "";
  return `<tr><td><a href="#/replays/${encodeURIComponent(r.id)}">${name}</a>${started}</td>` +
    `<td>${escapeHtml(r.sport)}</td><td>${replayState(r, recording)}</td>` +
    `<td>${escapeHtml(formatScore(r.sport, r.result))}</td><td>${file}</td></tr>`;
}

/** Says how many replays are not shown, if the listing has more pages. */
function moreRow(recorded) {
  if (!recorded.next) return "";
  const total = Number(recorded.total);
  const shown = recorded.replays.length;
  const more = Number.isFinite(total) && total > shown ? `${total - shown} older` : "older";
  return `<tr><td colspan="5" class="muted">the newest ${shown} shown; ${escapeHtml(more)} not listed here</td></tr>`;
}

function replayState(r, recording) {
  if (recording) return "recording (match live)";
  if (!r.complete) return "cut short";
  if (r.reason === "rotated") return "complete (continues in the next part)";
  if (r.reason === "size_limit") return "stopped at the size limit";
  return "complete";
}

function size(bytes) {
  return bytes >= 1e6 ? `${(bytes / 1e6).toFixed(1)} MB` : `${Math.max(1, Math.round(bytes / 1e3))} kB`;
}
