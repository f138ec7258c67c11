// Basketball: the half court, the players as oriented markers with the motion they move
// with, the ball; the selected player's cost map (its physical capability from motion
// capture: seconds to reach each square) laid on the court at its pose; and its latest
// decision in words and graphics, the safe squares outlined.
import { $, FieldMap, MARKER_PX, NARROW_PX, costColour, escapeHtml, fitCanvas, marker, nearest, trace } from "./draw.js";
import { Labels } from "./labels.js";

const TEAM_COLOURS = { offense: "#3d6fe0", defense: "#e0483d" };
const OVERLAY_ALPHA = 0.42;

export class CourtView {
  /** A replay seek asks for this much lead-in: enough for the holder's latest decision. */
  leadInS = 5;

  constructor(hello) {
    this.field = hello.match.field;
    this.court = this.field.court;
    this.agents = hello.match.agents;
    /** Teams never change, so frames leave them out: they are in the hello. */
    this.teams = new Map(this.agents.map((a) => [a.id, a.team]));
    /** Cost maps by behaviour: fetched once each; a map is the same at every pose. */
    this.costmaps = new Map();
    /** What of the ground the picture shows: the half court and a margin for its lines. */
    const margin = 0.25, half = this.court.width_m / 2;
    this.frame = { bounds: [-margin, this.court.length_m + margin, -half - margin, half + margin], rotation: 0 };
    this.reset();
  }

  reset() {
    this.decisions = new Map();
    this.shot = null;
  }

  apply(frame) {
    for (const e of frame.events) {
      if (e.kind === "decision") {
        this.decisions.set(e.agent, { ...e, safe: safeSquares(this.court, e.safe), time_s: frame.time_s });
      }
      if (e.kind === "shot") this.shot = { ...e, time_s: frame.time_s };
    }
  }

  describe(e) {
    switch (e.kind) {
      case "decision": return `${e.agent}: ${e.reason}`;
      case "pass": return `${e.from} passes to ${e.to}`;
      case "pass_caught": return `${e.by} catches the pass`;
      case "shot": {
        const result = e.blocked ? "blocked" : e.made ? `made, ${e.points} points` : "missed";
        return `${e.by} shoots from ${e.distance_m.toFixed(1)} m (${(100 * e.success).toFixed(0)} % chance): ${result}`;
      }
      case "possession_ended":
        return `possession ${e.possession}: ${e.outcome.replace("_", " ")}, ${e.points} points, ` +
          `${e.duration_s.toFixed(1)} s, ${e.passes} passes`;
      default: return null;
    }
  }

  costmap(behaviour) {
    if (!this.costmaps.has(behaviour)) {
      const entry = { map: null, image: null, error: null };
      this.costmaps.set(behaviour, entry);
      fetch(`/api/costmaps/${encodeURIComponent(behaviour)}`)
        .then(async (r) => {
          const body = await r.json();
          if (!r.ok) throw new Error(body.error?.message ?? `HTTP ${r.status}`);
          entry.map = body;
          entry.image = costImage(body);
        })
        .catch((e) => {
          entry.error = e.message;
          // Ask again later: the server may have been away.
          setTimeout(() => this.costmaps.delete(behaviour), 5000);
        });
    }
    return this.costmaps.get(behaviour);
  }

  draw(canvas, sample, selected) {
    const { g, width, height } = fitCanvas(canvas);
    const c = this.court;
    const map = (this.lastMap = new FieldMap(width, height, this.frame.bounds, this.frame.rotation));
    g.fillStyle = "#2b2b2b";
    g.fillRect(0, 0, width, height);
    const [x0, z0] = map.px(0, -c.width_m / 2);
    const [x1, z1] = map.px(c.length_m, c.width_m / 2);
    g.fillStyle = "#d9a865";
    g.fillRect(x0, z0, x1 - x0, z1 - z0);

    const agent = sample.agents.find((a) => a.id === selected);
    if (agent) {
      g.save();
      g.beginPath(); g.rect(x0, z0, x1 - x0, z1 - z0); g.clip();
      this.drawCostmap(g, map, agent);
      g.restore();
    }
    this.drawLines(g, map);
    const decision = this.decisions.get(selected);
    if (decision && agent) this.drawDecision(g, map, agent, decision);

    const labels = new Labels(g, width, height);
    const named = [];
    for (const a of sample.agents) {
      const [x, y] = marker(g, map, a.position, a.heading, {
        fill: TEAM_COLOURS[this.teams.get(a.id)] ?? "#fff",
        selected: a.id === selected,
      });
      labels.avoid(x, y, MARKER_PX);
      const text = width < NARROW_PX
        ? a.id
        : `${a.id} · ${a.behaviour} · ${a.action.replaceAll("_", " ")}${a.controller === "bot" ? " (bot)" : ""}`;
      named.push({ text, x, y, first: a.id === selected });
    }
    const [bx, by] = this.drawBall(g, map, sample);
    labels.avoid(bx, by, 8);
    // The selected agent's name is placed first: it gets the spot nearest its marker.
    named.sort((a, b) => b.first - a.first);
    for (const n of named) labels.add(n.text, n.x, n.y);
    labels.draw(canvas);
  }

  drawLines(g, map) {
    const c = this.court, [bx, bz] = c.basket, half = c.width_m / 2;
    g.strokeStyle = "#fff";
    g.lineWidth = 2;
    const line = (...points) => {
      trace(g, map, points);
      g.stroke();
    };
    line([0, -half], [c.length_m, -half], [c.length_m, half], [0, half], [0, -half]);
    // The key (4.9 m wide, 5.8 m to the free-throw line) and its circle.
    line([0, -2.45], [5.8, -2.45], [5.8, 2.45], [0, 2.45]);
    const [fx, fz] = map.px(5.8, 0);
    g.beginPath(); g.arc(fx, fz, 1.8 * map.scale, 0, 2 * Math.PI); g.stroke();
    // The three-point line: straight 0.9 m inside each sideline, then the arc.
    const r = c.three_point_m, side = half - 0.9;
    const corner = bx + Math.sqrt(Math.max(0, r * r - side * side));
    line([0, -side], [corner, -side]);
    line([0, side], [corner, side]);
    const [px, pz] = map.px(bx, bz);
    const a = Math.asin(Math.min(1, side / r));
    g.beginPath(); g.arc(px, pz, r * map.scale, -a, a); g.stroke();
    // Backboard and ring.
    line([1.2, -0.9], [1.2, 0.9]);
    g.strokeStyle = "#ff6a00"; g.lineWidth = 2.5;
    g.beginPath(); g.arc(px, pz, 0.23 * map.scale, 0, 2 * Math.PI); g.stroke();
    // Half-court line's circle.
    g.strokeStyle = "#fff"; g.lineWidth = 2;
    const [hx, hz] = map.px(c.length_m, 0);
    g.beginPath(); g.arc(hx, hz, 1.8 * map.scale, Math.PI / 2, 1.5 * Math.PI); g.stroke();
  }

  /** The selected agent's cost map, drawn in its own frame at its pose. */
  drawCostmap(g, map, agent) {
    const entry = this.costmap(agent.behaviour);
    if (!entry.image) return;
    const m = entry.map, image = entry.image;
    const [ax, ay] = map.px(...agent.position);
    g.save();
    g.translate(ax, ay);
    g.rotate(map.angle(agent.heading));
    g.scale(map.scale, map.scale);
    // Smoothed between cell centres: the map samples a continuous time-to-reach, and
    // drawn as hard cells turned to the agent's heading its edges were staircases.
    g.imageSmoothingEnabled = true;
    g.imageSmoothingQuality = "high";
    g.drawImage(image, m.origin[0], m.origin[1], image.width * m.cell_m, image.height * m.cell_m);
    g.restore();
  }

  /** The safe squares of the agent's latest decision outlined, the chosen one bold. */
  drawDecision(g, map, agent, decision) {
    const half = this.court.square_m / 2;
    const square = (cell) => {
      const [x, y] = map.px(cell[0] - half, cell[1] - half);
      const s = 2 * half * map.scale;
      g.strokeRect(x, y, s, s);
    };
    g.strokeStyle = "rgba(255,255,255,.9)";
    g.lineWidth = 1;
    for (const cell of decision.safe) square(cell);
    if (decision.chosen) {
      g.strokeStyle = "#ffd400";
      g.lineWidth = 3;
      square(decision.chosen.cell);
      g.setLineDash([5, 4]);
      g.lineWidth = 1.5;
      trace(g, map, [agent.position, decision.chosen.cell]);
      g.stroke();
      g.setLineDash([]);
    }
  }

  drawBall(g, map, sample) {
    const ball = sample.ball;
    let [x, y, z] = ball.position;
    const holder = ball.holder && sample.agents.find((a) => a.id === ball.holder);
    // A held ball is drawn at its holder's side, so it moves with the interpolated player.
    if (holder) {
      x = holder.position[0] + 0.35 * Math.cos(holder.heading + 0.8);
      z = holder.position[1] + 0.35 * Math.sin(holder.heading + 0.8);
      y = 1;
    }
    const [sx, sy] = map.px(x, z);
    const lift = ball.state === "held" ? 0 : Math.min(y * map.scale * 0.35, 60);
    g.fillStyle = "rgba(0,0,0,.3)";
    g.beginPath(); g.ellipse(sx, sy, 6, 4, 0, 0, 2 * Math.PI); g.fill();
    g.fillStyle = "#f07c1e"; g.strokeStyle = "#402000"; g.lineWidth = 1.5;
    g.beginPath(); g.arc(sx, sy - lift, 6, 0, 2 * Math.PI); g.fill(); g.stroke();
    return [sx, sy - lift];
  }

  pick(px, py, sample) {
    return nearest(this.lastMap, px, py, sample);
  }

  drawPanels(sample, selected) {
    const agent = sample.agents.find((a) => a.id === selected);
    const decision = this.decisions.get(selected);
    const byBot = agent?.controller === "bot";
    $("decision").innerHTML = decision
      ? explain(decision, this.field.decision, sample.time_s, byBot)
      : byBot
        ? `${escapeHtml(selected)} is moved by a connected bot; no order has changed what it does since you started watching.`
        : `${escapeHtml(selected ?? "")} has made no decision since you started watching.`;
    const entry = agent && this.costmap(agent.behaviour);
    const horizon = entry?.map?.horizon_s ?? 8;
    $("costmap-text").textContent = !agent
      ? ""
      : entry.error
        ? `cost map unavailable: ${entry.error}`
        : `${agent.id} moves with "${agent.behaviour}": colour is the time a real person (motion capture) ` +
          `needs to reach each square from this pose; blank is beyond ${horizon} s.`;
    drawScale(fitCanvas($("scale")), horizon);
  }
}

/**
 * A cost map as an image, one pixel a cell, coloured once when it arrives: the map is
 * the same at every pose, so each animation frame only places it (one drawImage).
 */
function costImage(m) {
  const image = document.createElement("canvas");
  image.width = m.costs_s[0]?.length ?? 0;
  image.height = m.costs_s.length;
  const g = image.getContext("2d");
  m.costs_s.forEach((row, i) => row.forEach((seconds, j) => {
    if (seconds === null) return;
    g.fillStyle = costColour(seconds, m.horizon_s, OVERLAY_ALPHA);
    g.fillRect(j, i, 1, 1);
  }));
  return image;
}

/**
 * The centres of a decision's safe squares, from the bitmap it carries (PROTOCOL.md):
 * `box` is [first row, first column, rows, columns] of the court's squares (rows along z
 * from -width/2, columns along x from the baseline); bit r·columns + c of `bits` (base64,
 * least significant bit of each byte first) marks square (first row + r, first column + c).
 */
export function safeSquares(court, safe) {
  if (!safe) return [];
  const [i0, j0, rows, columns] = safe.box;
  const bytes = Uint8Array.from(atob(safe.bits), (ch) => ch.charCodeAt(0));
  const s = court.square_m;
  const cells = [];
  for (let bit = 0; bit < rows * columns; bit++) {
    if (bytes[bit >> 3] & (1 << (bit & 7))) {
      const i = i0 + Math.floor(bit / columns), j = j0 + (bit % columns);
      cells.push([(j + 0.5) * s, -court.width_m / 2 + (i + 0.5) * s]);
    }
  }
  return cells;
}

/** The protocol's `reason` of a decision a bot's order made (PROTOCOL.md). */
const BOT_ORDER = "bot order";

/**
 * A decision in words, with the numbers of the rule C_o > C_d + T_s + ε; `byBot`: a
 * connected bot moves the agent now.
 */
export function explain(d, rule, now, byBot) {
  const age = Math.max(0, now - d.time_s);
  const action = escapeHtml(String(d.action).replaceAll("_", " "));
  if (d.reason === BOT_ORDER) {
    // The bot chose; the rule was not applied, so there are no numbers to show.
    return `<b>${escapeHtml(d.agent)}</b> carries out its bot's order: ${action}.` +
      `<br><span class="muted">${byBot ? "A connected bot moves this player" : "A bot moved this player"}: ` +
      `the built-in rule (C<sub>o</sub> &gt; C<sub>d</sub> + T<sub>s</sub> + ε) does not decide for it. ` +
      `Ordered ${age.toFixed(1)} s ago.</span>`;
  }
  let text = `<b>${escapeHtml(d.agent)}</b> ${escapeHtml(d.reason)}`;
  const c = d.chosen;
  if (c) {
    // Numbers are coerced: a replay's frames are whatever its file holds.
    const [co, cd, ts, eps] = [c.c_o, c.c_d, rule.shot_time_s, rule.epsilon_s].map(Number);
    const margin = co - (cd + ts + eps);
    // A map's horizon is a bound: the defender needs at least that long, not that long.
    const needs = c.beyond_horizon === true ? `beyond ${co.toFixed(0)} s` : `${co.toFixed(1)} s`;
    text += `<br>C<sub>o</sub> ${needs} ${margin > 0 ? "&gt;" : "≤"} C<sub>d</sub> ${cd.toFixed(1)} s + ` +
      `T<sub>s</sub> ${ts.toFixed(1)} s + ε ${eps.toFixed(1)} s; shot success ${(100 * Number(c.success)).toFixed(0)} %`;
  }
  const n = Number(d.safe.length);
  text += `<br><span class="muted">${n} safe square${n === 1 ? "" : "s"} outlined; decided ${age.toFixed(1)} s ago.</span>`;
  return text;
}

function drawScale({ g, width, height }, horizon) {
  g.clearRect(0, 0, width, height);
  const bar = width - 60;
  for (let i = 0; i < bar; i++) {
    g.fillStyle = costColour((i / bar) * horizon, horizon);
    g.fillRect(30 + i, 0, 1, height - 10);
  }
  g.fillStyle = "#444";
  g.font = "10px system-ui, sans-serif";
  g.fillText("0 s", 0, height - 12);
  g.fillText(`${horizon} s`, width - 28, height - 12);
}
