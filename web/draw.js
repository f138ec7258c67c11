// Small helpers the views share: DOM look-ups, text, canvas sizing, the map from field
// metres to canvas pixels, and simple plots.

export const $ = (id) => document.getElementById(id);

export function escapeHtml(text) {
  return String(text).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}

/** A score as people say it, for each sport's `score` object (null: nothing yet). */
export function formatScore(sport, score) {
  if (!score) return "";
  if (sport === "basketball") return `${score.points} pts in ${score.possession} possessions`;
  return `${score.caught} caught, ${score.dropped} dropped of ${score.balls}`;
}

/** Seconds as m:ss.s. */
export function clock(seconds) {
  const m = Math.floor(seconds / 60);
  const s = (seconds - 60 * m).toFixed(1).padStart(4, "0");
  return `${m}:${s}`;
}

/**
 * Sizes a canvas's backing store to its CSS box times the device pixel ratio (sharp on
 * phones and high-density screens) and returns its context scaled to CSS pixels.
 */
export function fitCanvas(canvas) {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  const g = canvas.getContext("2d");
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  return { g, width: canvas.clientWidth, height: canvas.clientHeight };
}

/**
 * Field metres (x, z on the ground, as in the protocol) to canvas pixels: `rotation`
 * turns the field so its natural "up" is up; `bounds` [x0, x1, z0, z1] is the part of
 * the rotated field that must fit. The map is a rotation and a uniform scale, never a
 * mirror, so the picture is the field seen from above.
 */
export class FieldMap {
  constructor(width, height, bounds, rotation = 0) {
    const [x0, x1, z0, z1] = bounds;
    this.cos = Math.cos(rotation);
    this.sin = Math.sin(rotation);
    this.scale = Math.min(width / (x1 - x0), height / (z1 - z0));
    this.cx = (x0 + x1) / 2;
    this.cz = (z0 + z1) / 2;
    this.ox = width / 2;
    this.oy = height / 2;
  }

  /** Canvas pixels of a ground point. */
  px(x, z) {
    const u = x * this.cos - z * this.sin - this.cx;
    const v = x * this.sin + z * this.cos - this.cz;
    return [this.ox + u * this.scale, this.oy + v * this.scale];
  }

  /** The ground point under a canvas pixel. */
  ground(px, py) {
    const u = (px - this.ox) / this.scale + this.cx;
    const v = (py - this.oy) / this.scale + this.cz;
    return [u * this.cos + v * this.sin, -u * this.sin + v * this.cos];
  }

  /** A heading on the field as a canvas angle. */
  angle(heading) {
    return heading + Math.atan2(this.sin, this.cos);
  }
}

/** Begins a path through ground points; the caller strokes or fills it. */
export function trace(g, map, points) {
  g.beginPath();
  points.forEach(([x, z], i) => {
    const [px, py] = map.px(x, z);
    if (i) g.lineTo(px, py);
    else g.moveTo(px, py);
  });
}

/** The agent nearest a canvas point, within 24 px (a finger's reach). */
export function nearest(map, px, py, sample) {
  if (!map || !sample) return null;
  let best = null, bestD = 24;
  for (const a of sample.agents) {
    const [x, y] = map.px(a.position[0], a.position[1]);
    const d = Math.hypot(x - px, y - py);
    if (d < bestD) { best = a.id; bestD = d; }
  }
  return best;
}

/**
 * An agent as an oriented marker: a disc with a nose toward its heading. Returns its
 * canvas point (its label is placed by a `Labels` layout, which keeps labels apart).
 */
export function marker(g, map, position, heading, { fill, selected }) {
  const [x, y] = map.px(position[0], position[1]);
  const a = map.angle(heading);
  g.fillStyle = fill;
  g.strokeStyle = selected ? "#ffd400" : "#111";
  g.lineWidth = selected ? 3 : 1.5;
  g.beginPath();
  g.moveTo(x + 12 * Math.cos(a), y + 12 * Math.sin(a));
  g.arc(x, y, 7, a + 0.9, a - 0.9 + 2 * Math.PI);
  g.closePath();
  g.fill();
  g.stroke();
  return [x, y];
}

/** The half-side of the square a marker covers, px (its disc and its nose). */
export const MARKER_PX = 10;

/** Below this canvas width (a phone), agents are labelled by id alone. */
export const NARROW_PX = 560;

/**
 * A line plot's frame: axes with labels and the data range mapped to the box. Returns
 * a function from data (x, y) to pixels.
 */
export function plotFrame(g, width, height, { x: [x0, x1], y: [y0, y1], xLabel, yLabel }) {
  const left = 46, right = 10, top = 10, bottom = 34;
  const sx = (width - left - right) / (x1 - x0 || 1);
  const sy = (height - top - bottom) / (y1 - y0 || 1);
  const at = (x, y) => [left + (x - x0) * sx, height - bottom - (y - y0) * sy];
  g.strokeStyle = "#999";
  g.lineWidth = 1;
  g.strokeRect(left, top, width - left - right, height - top - bottom);
  g.fillStyle = "#555";
  g.font = "11px system-ui, sans-serif";
  g.textAlign = "center";
  g.fillText(xLabel, left + (width - left - right) / 2, height - 4);
  g.fillText(tickLabel(x0), left, height - bottom + 13);
  g.fillText(tickLabel(x1), width - right - 8, height - bottom + 13);
  g.save();
  g.translate(11, top + (height - top - bottom) / 2);
  g.rotate(-Math.PI / 2);
  g.fillText(yLabel, 0, 0);
  g.restore();
  g.textAlign = "right";
  g.fillText(tickLabel(y0), left - 3, height - bottom);
  g.fillText(tickLabel(y1), left - 3, top + 9);
  g.textAlign = "left";
  return at;
}

/** An axis end as people write it: 120, 42, 1.7, 0.25. */
function tickLabel(v) {
  return Math.abs(v) >= 10 ? v.toFixed(0) : String(Number(v.toPrecision(2)));
}

/** Least-squares line y = a + b·x and its R² (1 for a perfect line). */
export function fitLine(points) {
  const n = points.length;
  if (n < 3) return null;
  let sx = 0, sy = 0;
  for (const [x, y] of points) { sx += x; sy += y; }
  const mx = sx / n, my = sy / n;
  let sxx = 0, sxy = 0, syy = 0;
  for (const [x, y] of points) {
    sxx += (x - mx) ** 2; sxy += (x - mx) * (y - my); syy += (y - my) ** 2;
  }
  if (sxx === 0) return null;
  const b = sxy / sxx;
  const r2 = syy === 0 ? 1 : (sxy * sxy) / (sxx * syy);
  return { a: my - b * mx, b, r2 };
}

/** The colour of a cost in seconds on a 0..horizon scale: near is warm, far is cool. */
export function costColour(seconds, horizon, alpha = 1) {
  const f = Math.min(1, Math.max(0, seconds / horizon));
  const hue = 10 + 220 * f; // red (reached at once) through yellow and green to blue
  return `hsla(${hue.toFixed(0)}, 85%, 50%, ${alpha})`;
}
