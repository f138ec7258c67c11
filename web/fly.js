// Fly balls (baseball and cricket): the field from above with the ball, its shadow and
// height, the fielders with their trails and strategies, caught and missed balls
// marked; a side view of the flight; and the selected fielder's eye (eye.js).
import { $, FieldMap, MARKER_PX, NARROW_PX, fitCanvas, marker, nearest, plotFrame, trace } from "./draw.js";
import { drawEye, opticalSamples } from "./eye.js";
import { Labels } from "./labels.js";

/** How long a catch or a miss stays marked on the field, in match seconds. */
const MARK_S = 8;
/** The eye height fielders had before `hello` said it (replays recorded earlier). */
const DEFAULT_EYE_M = 1.7;
const FIELDER_COLOURS = ["#f4f4f4", "#ffd28a", "#b8e1ff", "#ffc2d4", "#d7f5b0", "#e2ccff"];

export class FlyView {
  /** A replay seek asks for this much lead-in: a whole flight (PROTOCOL.md, `seek`). */
  leadInS = 10;

  constructor(hello) {
    this.field = hello.match.field;
    this.eye = this.field.eye_height_m ?? DEFAULT_EYE_M;
    this.agents = hello.match.agents;
    this.colours = new Map(this.agents.map((a, i) => [a.id, FIELDER_COLOURS[i % FIELDER_COLOURS.length]]));
    // What of the ground the picture shows: the cricket ring, or baseball's fair
    // territory turned so centre field (azimuth 45°) points up.
    const r = this.field.kind === "cricket" ? this.field.boundary_m + 4 : this.field.fence_m;
    this.frame = this.field.kind === "cricket"
      ? { bounds: [-r, r, -r, r], rotation: 0 }
      : { bounds: [-0.75 * r, 0.75 * r, -1.04 * r, 0.08 * r], rotation: -0.75 * Math.PI };
    this.reset();
  }

  /** Forgets everything seen (a seek, a reconnection). */
  reset() {
    this.flight = [];
    this.marks = [];
    this.landing = null;
    this.outcome = null;
  }

  /** Takes a frame whose moment has come: its events, and the flight so far. */
  apply(frame) {
    for (const e of frame.events) {
      if (e.kind === "launch") {
        this.flight = [];
        this.landing = e.landing;
        this.outcome = null;
        // The last ball's catch or miss is its story; the new flight starts a clean field.
        this.marks = [];
      } else if (e.kind === "caught") {
        this.marks.push({ at: e.at, caught: true, label: `caught by ${e.by}`, t: frame.time_s });
        this.outcome = `Caught by ${e.by} after ${e.flight_time_s.toFixed(1)} s`;
        this.landing = null;
      } else if (e.kind === "landed") {
        this.marks.push({ at: e.at, caught: false, label: `missed by ${e.miss_m.toFixed(1)} m`, t: frame.time_s });
        this.outcome = `Landed ${e.miss_m.toFixed(1)} m from ${e.nearest}`;
        this.landing = null;
      }
    }
    if (frame.ball.state === "flight") {
      this.flight.push({
        t: frame.time_s,
        ball: frame.ball.position,
        agents: Object.fromEntries(frame.agents.map((a) => [a.id, a.position])),
      });
    }
    this.marks = this.marks.filter((m) => frame.time_s - m.t < MARK_S);
  }

  describe(e) {
    const xz = (p) => `(${p[0].toFixed(1)}, ${p[1].toFixed(1)})`;
    switch (e.kind) {
      case "launch": {
        const l = e.launch;
        return `ball ${e.ball}: hit at ${l.speed_m_s.toFixed(1)} m/s, ${l.elevation_deg.toFixed(0)}° up, ` +
          `azimuth ${l.azimuth_deg.toFixed(0)}°; would land at ${xz(e.landing)}`;
      }
      case "caught": return `ball ${e.ball}: caught by ${e.by} at ${xz(e.at)} after ${e.flight_time_s.toFixed(2)} s`;
      case "landed": return `ball ${e.ball}: landed at ${xz(e.at)}, ${e.miss_m.toFixed(1)} m from ${e.nearest}`;
      default: return null;
    }
  }


  draw(canvas, sample, selected) {
    const { g, width, height } = fitCanvas(canvas);
    const map = (this.lastMap = new FieldMap(width, height, this.frame.bounds, this.frame.rotation));
    g.fillStyle = "#3f7d3a";
    g.fillRect(0, 0, width, height);
    if (this.field.kind === "cricket") this.drawOval(g, map);
    else this.drawDiamond(g, map);

    // Where the ball would land if nobody caught it (from the launch event).
    if (this.landing) {
      const [x, y] = map.px(...this.landing);
      g.setLineDash([4, 4]);
      g.strokeStyle = "rgba(255,255,255,.7)";
      g.lineWidth = 1.5;
      g.beginPath(); g.arc(x, y, 9, 0, 2 * Math.PI); g.stroke();
      g.setLineDash([]);
    }
    const labels = new Labels(g, width, height);
    for (const m of this.marks) this.drawMark(g, map, m, labels);

    // Trails: each fielder's run since the launch.
    for (const a of this.agents) {
      const points = this.flight.map((s) => s.agents[a.id]).filter(Boolean);
      if (points.length < 2) continue;
      g.strokeStyle = a.id === selected ? "#ffd400" : "rgba(255,255,255,.55)";
      g.lineWidth = a.id === selected ? 2.5 : 1.5;
      trace(g, map, points);
      g.stroke();
    }
    const named = [];
    for (const a of sample.agents) {
      const [x, y] = marker(g, map, a.position, a.heading, {
        fill: this.colours.get(a.id) ?? "#fff",
        selected: a.id === selected,
      });
      labels.avoid(x, y, MARKER_PX);
      const text = width < NARROW_PX ? a.id : `${a.id} · ${a.controller === "bot" ? "bot" : a.strategy}`;
      named.push({ text, x, y, first: a.id === selected });
    }
    this.drawBall(g, map, sample.ball, labels);
    // The selected agent's name is placed first: it gets the spot nearest its marker.
    named.sort((a, b) => b.first - a.first);
    for (const n of named) labels.add(n.text, n.x, n.y);
    labels.draw(canvas);
  }

  drawDiamond(g, map) {
    const f = this.field, r = f.fence_m, b = f.base_path_m;
    const poly = (points, fill, stroke) => {
      trace(g, map, points);
      g.closePath();
      if (fill) { g.fillStyle = fill; g.fill(); }
      if (stroke) { g.strokeStyle = stroke; g.stroke(); }
    };
    const arc = (radius, steps = 48) =>
      Array.from({ length: steps + 1 }, (_, i) => {
        const a = (i / steps) * (Math.PI / 2);
        return [radius * Math.cos(a), radius * Math.sin(a)];
      });
    poly([[0, 0], ...arc(r)], "#4c9a45", null);
    poly([[0, 0], ...arc(1.1 * b)], "#b98b55", null);
    poly([[0, 0], [b, 0], [b, b], [0, b]], "#4c9a45", "#fff");
    g.lineWidth = 3;
    g.strokeStyle = "#f0e6c8";
    trace(g, map, arc(r));
    g.stroke();
    g.lineWidth = 1.5;
    g.strokeStyle = "#fff";
    for (const end of [[r, 0], [0, r]]) {
      trace(g, map, [[0, 0], end]);
      g.stroke();
    }
    g.fillStyle = "#fff";
    for (const base of [[0, 0], [b, 0], [b, b], [0, b]]) {
      const [x, y] = map.px(...base);
      g.fillRect(x - 3, y - 3, 6, 6);
    }
  }

  drawOval(g, map) {
    const f = this.field;
    const [cx, cy] = map.px(0, 0);
    g.fillStyle = "#4c9a45";
    g.beginPath(); g.arc(cx, cy, f.boundary_m * map.scale, 0, 2 * Math.PI); g.fill();
    g.strokeStyle = "#fff"; g.lineWidth = 3; g.stroke();
    g.setLineDash([6, 6]); g.lineWidth = 1.5;
    g.beginPath(); g.arc(cx, cy, f.inner_ring_m * map.scale, 0, 2 * Math.PI); g.stroke();
    g.setLineDash([]);
    // The pitch runs from the batter's stumps to the bowler's, 3.05 m wide.
    const w = 1.525;
    g.fillStyle = "#d9c38f";
    trace(g, map, [[0, -w], [-f.pitch_length_m, -w], [-f.pitch_length_m, w], [0, w]]);
    g.closePath(); g.fill();
  }

  drawMark(g, map, m, labels) {
    const [x, y] = map.px(...m.at);
    g.lineWidth = 3;
    g.strokeStyle = m.caught ? "#27c93f" : "#ff4d4d";
    g.beginPath();
    if (m.caught) g.arc(x, y, 11, 0, 2 * Math.PI);
    else { g.moveTo(x - 8, y - 8); g.lineTo(x + 8, y + 8); g.moveTo(x + 8, y - 8); g.lineTo(x - 8, y + 8); }
    g.stroke();
    labels.avoid(x, y, 12);
    labels.add(m.label, x, y, { font: "bold 12px system-ui, sans-serif", fill: m.caught ? "#0b5d1e" : "#9b1010", rank: 1 });
  }

  /** The ball's shadow on the ground, and the ball above it by its height. */
  drawBall(g, map, ball, labels) {
    if (ball.state !== "flight") return;
    const [x, y, z] = ball.position;
    const [sx, sy] = map.px(x, z);
    const lift = Math.min(y * map.scale * 0.6, 120);
    g.fillStyle = "rgba(0,0,0,.35)";
    g.beginPath(); g.ellipse(sx, sy, 5, 3, 0, 0, 2 * Math.PI); g.fill();
    g.strokeStyle = "rgba(255,255,255,.5)"; g.lineWidth = 1;
    g.beginPath(); g.moveTo(sx, sy); g.lineTo(sx, sy - lift); g.stroke();
    g.fillStyle = "#fff"; g.strokeStyle = "#c00"; g.lineWidth = 1.5;
    g.beginPath(); g.arc(sx, sy - lift, 5, 0, 2 * Math.PI); g.fill(); g.stroke();
    labels.avoid(sx, sy - lift, 7);
    labels.avoid(sx, sy, 5);
    labels.add(`${y.toFixed(1)} m`, sx, sy - lift, { font: "11px system-ui, sans-serif", fill: "#fff", halo: "rgba(0,0,0,.45)", rank: 2 });
  }

  /** The agent under a canvas point, if one is within reach of a finger. */
  pick(px, py, sample) {
    return nearest(this.lastMap, px, py, sample);
  }

  drawPanels(sample, selected) {
    const agent = this.agents.find((a) => a.id === selected);
    const eye = fitCanvas($("eye"));
    $("eye-text").textContent = drawEye(eye.g, eye.width, eye.height, {
      samples: opticalSamples(this.flight, selected, this.eye),
      strategy: sample.agents.find((a) => a.id === selected)?.controller === "bot" ? "bot" : agent?.strategy ?? "",
      fielder: selected,
      outcome: this.outcome,
    });
    this.drawSide(fitCanvas($("side")), sample, selected);
  }

  /** The flight from the side: height against distance from home, the fielders below. */
  drawSide({ g, width, height }, sample, selected) {
    g.clearRect(0, 0, width, height);
    const reach = this.field.fence_m ?? this.field.boundary_m;
    const top = Math.max(20, ...this.flight.map((s) => s.ball[1] * 1.1));
    const at = plotFrame(g, width, height, {
      x: [0, reach * 1.05], y: [0, top], xLabel: "distance from home (m)", yLabel: "height (m)",
    });
    g.strokeStyle = "#f0e6c8"; g.lineWidth = 3;
    g.beginPath(); g.moveTo(...at(reach, 0)); g.lineTo(...at(reach, Math.min(top, 3))); g.stroke();
    if (this.flight.length > 1) {
      g.strokeStyle = "#c00"; g.lineWidth = 2;
      g.beginPath();
      this.flight.forEach((s, i) => {
        const p = at(Math.hypot(s.ball[0], s.ball[2]), s.ball[1]);
        if (i) g.lineTo(...p); else g.moveTo(...p);
      });
      g.stroke();
    }
    for (const a of sample.agents) {
      const [x, y] = at(Math.hypot(...a.position), 0);
      g.fillStyle = a.id === selected ? "#d4a000" : "#555";
      g.fillRect(x - 2, y - (a.id === selected ? 18 : 12), 4, a.id === selected ? 18 : 12);
    }
  }
}

