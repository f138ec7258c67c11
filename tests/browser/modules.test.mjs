// The page's pure modules against analytic oracles, in Node (no browser needed):
// the fielder's-eye optics (eye.js), line fits (draw.js) and frame interpolation
// (timeline.js), the decoding of a decision's safe squares (court.js) and how long the
// field keeps a catch or a miss marked (fly.js), and the label layout (labels.js). Run by
// tests/browser.rs with `node --test`.
import assert from "node:assert/strict";
import { test } from "node:test";
import { explain, safeSquares } from "../../web/court.js";
import { fitLine } from "../../web/draw.js";
import { opticalSamples, straightness } from "../../web/eye.js";
import { Labels } from "../../web/labels.js";
import { Timeline } from "../../web/timeline.js";

const EYE = 1.7;

/**
 * A flight built so that, seen from a fielder at (60, 0) looking at home (0, 0), tan ψ
 * is exactly k·t (Chapman's constant rate) and the image point's lateral coordinate is
 * c times its vertical one (a straight image path, McBeath's LOT): the ball comes in
 * along the home line, depth(t) = 50 − 5t, height eye + k·t·depth, and sideways
 * c·k·t·depth. (Its ground distance is not its depth when c ≠ 0, so tan ψ uses the
 * ground distance: the oracle below accounts for it.)
 */
function flight({ k, c, steps = 60 }) {
  const samples = [];
  for (let i = 1; i <= steps; i++) {
    const t = i / 30;
    const depth = 50 - 5 * t;
    const rise = k * t * depth;
    samples.push({ t, ball: [60 - depth, EYE + rise, c * rise], agents: { cf: [60, 0] } });
  }
  return samples;
}

test("tan ψ is height over ground distance, and rises at exactly k with R² 1 on a line", () => {
  const k = 0.23;
  const seen = opticalSamples(flight({ k, c: 0 }), "cf", EYE);
  assert.ok(seen.length > 50);
  for (const s of seen) assert.ok(Math.abs(s.tanPsi - k * s.t) < 1e-12, `${s.tanPsi} at ${s.t}`);
  const fit = fitLine(seen.map((s) => [s.t, s.tanPsi]));
  assert.ok(Math.abs(fit.b - k) < 1e-9 && Math.abs(fit.a) < 1e-9 && fit.r2 > 1 - 1e-12, JSON.stringify(fit));
});

test("the image point is (lateral, height above the eye) over depth toward home", () => {
  const seen = opticalSamples(flight({ k: 0.2, c: 0.5 }), "cf", EYE);
  for (const s of seen) {
    // v = k t exactly (height over depth), u = −c v: u counts to the right of a
    // fielder facing home, and facing −x, +z (where the ball drifts) is its left.
    assert.ok(Math.abs(s.v - 0.2 * s.t) < 1e-12);
    assert.ok(Math.abs(s.u + 0.5 * s.v) < 1e-12);
  }
  assert.ok(straightness(seen.map((s) => [s.u, s.v])) > 1 - 1e-12);
});

test("a curved image path is measurably less straight than a line", () => {
  // u = v² over v in 0..1: the principal-axis ratio of a parabola arc is below 1.
  const points = Array.from({ length: 50 }, (_, i) => [(i / 49) ** 2, i / 49]);
  const s = straightness(points);
  assert.ok(s < 0.999 && s > 0.9, `${s}`);
});

test("balls below the eye or within 2 m are not counted, as in the sweep", () => {
  const samples = [
    { t: 0, ball: [0, EYE - 0.5, 0], agents: { cf: [30, 0] } },
    { t: 1, ball: [29, 10, 0], agents: { cf: [30, 0] } },
    { t: 2, ball: [20, EYE + 0.1, 0], agents: { cf: [30, 0] } },
  ];
  assert.deepEqual(opticalSamples(samples, "cf", EYE), []);
});

function frame(tick, x, heading, state = "flight") {
  return {
    tick, time_s: tick / 60, score: {}, events: [],
    ball: { state, position: [x, 1, 0] },
    agents: [{ id: "a", position: [x, 2 * x], heading }],
  };
}

test("between two frames the world is interpolated linearly, headings the short way round", () => {
  const t = new Timeline();
  t.push(frame(0, 0, 3.1));
  t.push(frame(2, 1, -3.1));
  t.clock = 1 / 60; // halfway
  const s = t.sample();
  assert.ok(Math.abs(s.agents[0].position[0] - 0.5) < 1e-12);
  assert.ok(Math.abs(s.agents[0].position[1] - 1.0) < 1e-12);
  // 3.1 to −3.1 is 0.083 rad through π, not 6.2 rad through 0.
  const h = s.agents[0].heading;
  assert.ok(Math.abs(Math.cos(h) - Math.cos(Math.PI)) < 1e-3, `${h}`);
  assert.ok(Math.abs(s.ball.position[0] - 0.5) < 1e-12);
});

test("a ball that changes state jumps rather than gliding", () => {
  const t = new Timeline();
  t.push(frame(0, 50, 0, "flight"));
  t.push(frame(2, 0, 0, "dead"));
  t.clock = 1 / 60;
  assert.equal(t.sample().ball.position[0], 50);
});

test("the clock plays behind the newest frame at the given rate, and hands over due frames once", () => {
  const t = new Timeline();
  for (let tick = 0; tick <= 60; tick += 2) t.push(frame(tick, tick, 0));
  let due = t.advance(0, 1, 0.1);
  assert.ok(Math.abs(t.clock - (1 - 0.1)) < 1e-12, `${t.clock}`);
  assert.equal(due[due.length - 1].tick, 54);
  due = t.advance(0.05, 1, 0.1);
  assert.ok(t.clock <= 1 + 1e-12);
  assert.ok(due.every((f) => f.tick > 54), "each frame's events are handed over once");
  // Paused (rate 0): exactly the newest frame.
  t.advance(0.5, 0, 0);
  assert.equal(t.sample().tick, 60);
  // A frame from the past (a seek backwards) starts again.
  t.push(frame(10, 10, 0));
  assert.equal(t.frames.length, 1);
});

test("a decision's safe squares decode to the centres of exactly the squares whose bits are set", () => {
  const court = { square_m: 0.5, width_m: 15 };
  // Worked by hand: rows 3-4, columns 5-7; bits 0 and 5 of one byte (0b100001, base64
  // "IQ==") are squares (3, 5) and (4, 7), centred at x = (j + ½)·0.5, z = −7.5 + (i + ½)·0.5.
  assert.deepEqual(safeSquares(court, { box: [3, 5, 2, 3], bits: "IQ==" }), [[2.75, -5.75], [3.75, -5.25]]);
  // The whole 28 × 30 court with every third square set, least significant bit first.
  const [rows, columns] = [30, 28];
  const bytes = new Uint8Array(Math.ceil((rows * columns) / 8));
  const expected = [];
  for (let bit = 0; bit < rows * columns; bit++) {
    if (bit % 3 !== 0) continue;
    bytes[bit >> 3] |= 1 << (bit & 7);
    const [i, j] = [Math.floor(bit / columns), bit % columns];
    expected.push([(j + 0.5) * 0.5, -7.5 + (i + 0.5) * 0.5]);
  }
  const bits = Buffer.from(bytes).toString("base64");
  assert.equal(bits.length, 140);
  assert.deepEqual(safeSquares(court, { box: [0, 0, rows, columns], bits }), expected);
  assert.deepEqual(safeSquares(court, null), []);
});

test("a decision reads the defender's horizon as a bound, and its own time as a time", () => {
  const rule = { shot_time_s: 0.4, epsilon_s: 0.2 };
  const decision = (chosen) => ({
    agent: "o1", action: "dribble_to_shot", reason: "dribbles to shoot", time_s: 1,
    chosen: { cell: [2.25, 0.25], success: 0.6, c_d: 2.5, here: false, ...chosen }, safe: { length: 3 },
  });
  const beyond = explain(decision({ c_o: 8, beyond_horizon: true }), rule, 1.5, false);
  assert.match(beyond, /C<sub>o<\/sub> beyond 8 s &gt; C<sub>d<\/sub> 2\.5 s/);
  assert.doesNotMatch(beyond, /8\.0 s/);
  const timed = explain(decision({ c_o: 4.25 }), rule, 1.5, false);
  assert.match(timed, /C<sub>o<\/sub> 4\.3 s &gt;/);
  assert.doesNotMatch(timed, /beyond/);
});

test("a catch or a miss stays marked until the next ball is hit, and no longer", async () => {
  const { FlyView } = await import("../../web/fly.js");
  const hello = { match: { field: { kind: "baseball", fence_m: 110 }, agents: [{ id: "cf" }] } };
  const view = new FlyView(hello);
  const frame = (time_s, events) => ({ time_s, events, ball: { state: "ground", position: [0, 0, 0] }, agents: [] });
  view.apply(frame(1, [{ kind: "landed", ball: 1, at: [50, 50], miss_m: 11.7, nearest: "cf" }]));
  assert.equal(view.marks.length, 1);
  view.apply(frame(2, [{ kind: "launch", ball: 2, launch: {}, landing: [60, 40] }]));
  assert.equal(view.marks.length, 0, "the previous ball's mark is gone when the next is hit");
  view.apply(frame(3, [{ kind: "caught", ball: 2, at: [60, 40], by: "cf", flight_time_s: 4 }]));
  view.apply(frame(3 + 7.9, []));
  assert.equal(view.marks.length, 1);
  view.apply(frame(3 + 8, []));
  assert.equal(view.marks.length, 0, "and a mark goes after 8 s with no new ball");
});

test("a runner's pose is phase-matched to the distance run: one loop later, the same pose", async () => {
  const { poseRunner, strideFor } = await import("../../web/pose.js");
  // Two joints, a root and a foot; a loop of four frames 2 m long at 4 m/s.
  const lib = {
    standing: 0,
    poses_mm: [[0, 1000, 0, 0, 0, 0], [0, 1000, 0, 500, 0, 0], [0, 1000, 0, 0, 0, 0], [0, 1000, 0, -500, 0, 0]],
    strides: [{ nodes: [0, 1, 2, 3], length_m: 2, speed_m_s: 4 }, { nodes: [1, 2], length_m: 1, speed_m_s: 2 }],
  };
  assert.equal(strideFor(lib, 3.5).speed_m_s, 4);
  assert.equal(strideFor(lib, 0.1), null);
  const a = poseRunner(lib, 4, 0.75, [10, 5], Math.PI / 2);
  const b = poseRunner(lib, 4, 2.75, [10, 5], Math.PI / 2);
  assert.deepEqual(a, b);
  // 0.75 m is 1.5 frames in: halfway from frame 1 (foot 0.5 m ahead) to frame 2 (0),
  // turned to face +z.
  assert.ok(Math.abs(a[1][2] - 5.25) < 1e-12 && Math.abs(a[1][0] - 10) < 1e-12, JSON.stringify(a));
});

/** A 2-D context that measures every character 7 px wide and draws nothing. */
const measuring = new Proxy({ measureText: (text) => ({ width: 7 * text.length }) }, {
  get: (g, name) => g[name] ?? (() => {}),
  set: () => true,
});

test("every label is placed inside the canvas and clear of the others, even crowded into a corner", () => {
  // Twelve names on one point in the corner of a small canvas: the rings around it hold
  // few, so most must go farther, and each that does gets a leader back to its anchor.
  const [width, height] = [200, 150];
  const labels = new Labels(measuring, width, height);
  labels.avoid(3, 3, 4);
  for (let k = 0; k < 12; k++) labels.add(`agent-${k}`, 3, 3);
  const placed = labels.draw({});
  assert.equal(placed.length, 12);
  for (const [i, a] of placed.entries()) {
    assert.ok(a.x0 >= 0 && a.y0 >= 0 && a.x1 <= width && a.y1 <= height, `${a.text} inside: ${JSON.stringify(a)}`);
    assert.ok(!(a.x0 < 7 && a.y0 < 7), `${a.text} clear of the marker`);
    for (const b of placed.slice(i + 1)) {
      assert.ok(a.x1 <= b.x0 || b.x1 <= a.x0 || a.y1 <= b.y0 || b.y1 <= a.y0, `${a.text} apart from ${b.text}`);
    }
  }
  const far = placed.filter((p) => Math.hypot((p.x0 + p.x1) / 2 - 3, (p.y0 + p.y1) / 2 - 3) > 80);
  assert.ok(far.length > 0 && far.every((p) => p.leader?.[0] === 3 && p.leader[1] === 3), "the far ones lead back to the anchor");
});

test("a label is left out only when the canvas has no room for it beside the others", () => {
  // A 100 × 15 px strip holds one 12-character label of 86 px (+4 padding), not two.
  const labels = new Labels(measuring, 100, 15);
  labels.add("abcdefghijkl", 50, 7);
  labels.add("mnopqrstuvwx", 50, 7);
  assert.deepEqual(labels.draw({}).map((p) => p.text), ["abcdefghijkl"]);
});
