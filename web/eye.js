// The fielder's-eye panel: what the selected fielder sees of the ball in flight.
//
// Two plots, computed from the frames exactly as the server's sweep measures them
// (crates/core/src/fielding/path_shape.rs), so the page and `fieldhouse catch-sweep` agree:
// * the image path: the ball projected on a vertical plane facing home plate from the
//   fielder, u = lateral offset / depth and v = (height − eye) / depth. McBeath's LOT
//   keeps it on a straight line; straightness is λmax/(λmax+λmin) of the points'
//   scatter (1 for a line).
// * tan ψ against time, ψ the ball's elevation above the eye. Chapman's optical
//   acceleration cancellation keeps it rising at a constant rate: R² of a line fit.
// Samples count once the ball is clearly above the eye (tan ψ > 0.05) and more than
// 2 m away, as in the sweep.
import { fitLine, plotFrame } from "./draw.js";

const CLEARLY_ABOVE_EYE_TAN_PSI = 0.05;

/** The optical samples of one fielder over a flight: [{t, tanPsi, u, v}]. */
export function opticalSamples(flight, fielder, eye, home = [0, 0]) {
  const out = [];
  for (const s of flight) {
    const at = s.agents[fielder];
    if (!at) continue;
    const rx = s.ball[0] - at[0], rz = s.ball[2] - at[1];
    const d = Math.hypot(rx, rz);
    const tanPsi = (s.ball[1] - eye) / d;
    if (!(d > 2 && tanPsi > CLEARLY_ABOVE_EYE_TAN_PSI)) continue;
    let fx = home[0] - at[0], fz = home[1] - at[1];
    const fl = Math.hypot(fx, fz) || 1;
    fx /= fl; fz /= fl;
    const depth = rx * fx + rz * fz;
    const sample = { t: s.t, tanPsi };
    if (depth > 0) {
      sample.u = (rx * -fz + rz * fx) / depth;
      sample.v = (s.ball[1] - eye) / depth;
    }
    out.push(sample);
  }
  return out;
}

/** λmax/(λmax+λmin) of a point cloud: 1 when the points lie on a line. */
export function straightness(points) {
  const n = points.length;
  if (n < 3) return null;
  let mu = 0, mv = 0;
  for (const [u, v] of points) { mu += u / n; mv += v / n; }
  let a = 0, b = 0, c = 0;
  for (const [u, v] of points) {
    a += (u - mu) ** 2 / n; b += (u - mu) * (v - mv) / n; c += (v - mv) ** 2 / n;
  }
  const half = (a + c) / 2, root = Math.sqrt(((a - c) / 2) ** 2 + b * b);
  const max = half + root, min = Math.max(0, half - root);
  return max <= 0 ? 1 : max / (max + min);
}

/**
 * Draws both plots on `g` (width × height CSS pixels) and returns a sentence saying
 * what they show.
 */
export function drawEye(g, width, height, { samples, strategy, fielder, outcome }) {
  g.clearRect(0, 0, width, height);
  const half = Math.floor(height / 2);
  if (samples.length < 2) {
    g.fillStyle = "#666";
    g.font = "13px system-ui, sans-serif";
    g.fillText(`waiting for a fly ball${fielder ? ` (${fielder})` : ""}…`, 12, 24);
    return "The fielder's view appears when the next ball is in the air.";
  }
  const image = samples.filter((s) => s.u !== undefined).map((s) => [s.u, s.v]);
  const tanPsi = samples.map((s) => [s.t, s.tanPsi]);

  // The image path, u to the right and v up; the u range is at least as wide as the v
  // range, so a path that hardly moves sideways looks as upright as it is.
  g.save();
  const us = image.map((p) => p[0]), vs = image.map((p) => p[1]);
  const vTop = Math.max(0.1, ...vs) * 1.05;
  const uLow = Math.min(0, ...us), uHigh = Math.max(0, ...us);
  const uPad = Math.max(0, vTop - (uHigh - uLow)) / 2 + 0.02;
  const at = plotFrame(g, width, half, {
    x: [uLow - uPad, uHigh + uPad], y: [0, vTop],
    xLabel: "where the fielder sees the ball: across", yLabel: "up",
  });
  path(g, image.map(([u, v]) => at(u, v)), "#1849a9");
  const lineR2 = straightness(image);
  g.restore();

  // tan ψ against time, with its least-squares line.
  g.save();
  g.translate(0, half);
  const t0 = tanPsi[0][0], t1 = tanPsi[tanPsi.length - 1][0];
  const top = Math.max(...tanPsi.map((p) => p[1])) * 1.05;
  const at2 = plotFrame(g, width, height - half, {
    x: [0, Math.max(0.5, t1 - t0)], y: [0, top], xLabel: "seconds since the ball rose above the eye", yLabel: "tan ψ",
  });
  const fit = fitLine(tanPsi.map(([t, p]) => [t - t0, p]));
  if (fit) {
    g.setLineDash([5, 4]);
    path(g, [at2(0, fit.a), at2(t1 - t0, fit.a + fit.b * (t1 - t0))], "#999");
    g.setLineDash([]);
  }
  path(g, tanPsi.map(([t, p]) => at2(t - t0, p)), "#b54708");
  g.restore();

  const r2 = (x) => (x === null || x === undefined ? "–" : x.toFixed(4));
  const rate = fit ? fit.b.toFixed(3) : "–";
  const result = outcome ? ` ${outcome}.` : "";
  return `${fielder} (${strategy}): tan ψ rises ${rate}/s, straightness R² ${r2(fit?.r2)} ` +
    `(Chapman's OAC keeps it 1); image path straightness ${r2(lineR2)} (McBeath's LOT keeps it 1).${result}`;
}

function path(g, points, colour) {
  if (points.length < 2) return;
  g.strokeStyle = colour;
  g.lineWidth = 2;
  g.beginPath();
  g.moveTo(...points[0]);
  for (const p of points.slice(1)) g.lineTo(...p);
  g.stroke();
}
