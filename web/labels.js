// Labels on the field that never cover each other, a marker or the ball.
//
// Names drawn at a fixed offset from their agents collided whenever agents met (two
// fielders under the same ball, the defender on the shooter, a catch marked where a
// fielder stands, the ball flying over a player). So a view draws its markers first,
// telling the layout what must stay visible (`avoid`), queues its labels most important
// first (`add`), and `draw` places each in the first free spot of a ring of candidates
// around its anchor, widening the ring until one fits, with a leader line when it had
// to move away. A label with no free spot within reach (crowded, or at the canvas's
// edge) goes to the nearest free spot anywhere on the canvas, still with its leader, so
// every name is shown; only a canvas with no room left at all leaves one out rather than
// draw it over another.
//
// What was placed stays on the canvas element (`placedLabels`, `labelObstacles`, in
// CSS pixels) so a test can check the picture without reading pixels.

/** Distances from the anchor tried in turn, px: the nearest spot that is free wins. */
const RINGS = [10, 20, 32, 46, 62, 80];
/** Directions around the anchor tried at each distance: up-right first, as before. */
const DIRECTIONS = [
  [1, -1], [-1, -1], [1, 1], [-1, 1], [0, -1], [0, 1], [1, 0], [-1, 0],
];
/** The grid a label that fits nowhere near its anchor is sought on, px. */
const SCAN_STEP = 4;
/** Room kept around a label, px. */
const PAD = 2;

export class Labels {
  constructor(g, width, height) {
    this.g = g;
    this.width = width;
    this.height = height;
    this.obstacles = [];
    this.queue = [];
    this.placed = [];
  }

  /** Keeps labels off a square of half-side `r` around (x, y): a marker, the ball. */
  avoid(x, y, r) {
    this.obstacles.push({ x0: x - r, y0: y - r, x1: x + r, y1: y + r });
  }

  /**
   * Queues `text` for the point (x, y). `font` (px size first: "bold 12px …"), `fill`
   * and `halo` (an outline so it reads on any ground; null for none); `rank`: labels are
   * placed by rank, then in the order added (agents' names 0, marks 1, the ball's 2).
   */
  add(text, x, y, { font = "12px system-ui, sans-serif", fill = "#111", halo = "rgba(255,255,255,.85)", rank = 0 } = {}) {
    this.queue.push({ text, x, y, font, fill, halo, rank });
  }

  /** Places and draws every queued label; returns the boxes placed. */
  draw(canvas) {
    const g = this.g;
    for (const label of this.queue.sort((a, b) => a.rank - b.rank)) {
      g.font = label.font;
      const w = g.measureText(label.text).width;
      const h = parseFloat(label.font.match(/(\d+(?:\.\d+)?)px/)?.[1] ?? "12") + 2;
      const box = this.spot(label.x, label.y, w, h);
      if (!box) continue;
      const moved = Math.hypot((box.x0 + box.x1) / 2 - label.x, (box.y0 + box.y1) / 2 - label.y) > RINGS[1] + w / 2;
      // A leader from the anchor to the label's nearest edge says whose it is.
      const leader = moved ? [label.x, label.y, clamp(label.x, box.x0, box.x1), clamp(label.y, box.y0, box.y1)] : null;
      this.placed.push({ ...box, text: label.text, leader });
      if (leader) {
        g.strokeStyle = "rgba(255,255,255,.7)";
        g.lineWidth = 1;
        g.beginPath();
        g.moveTo(leader[0], leader[1]);
        g.lineTo(leader[2], leader[3]);
        g.stroke();
      }
      g.textBaseline = "middle";
      const y = (box.y0 + box.y1) / 2;
      if (label.halo) {
        g.lineWidth = 3;
        g.strokeStyle = label.halo;
        g.strokeText(label.text, box.x0 + PAD, y);
      }
      g.fillStyle = label.fill;
      g.fillText(label.text, box.x0 + PAD, y);
      g.textBaseline = "alphabetic";
    }
    canvas.placedLabels = this.placed;
    canvas.labelObstacles = this.obstacles;
    return this.placed;
  }

  /**
   * The first free box of size w × h around (x, y), padding included: on the rings,
   * else the nearest free one anywhere on the canvas, else the nearest clear of the
   * other labels (over a marker); null only when no box is clear of the labels.
   */
  spot(x, y, w, h) {
    const bw = w + 2 * PAD, bh = h;
    for (const r of RINGS) {
      for (const [dx, dy] of DIRECTIONS) {
        // The box's corner (or edge middle) nearest the anchor sits `r` away from it.
        const x0 = dx > 0 ? x + r : dx < 0 ? x - r - bw : x - bw / 2;
        const y0 = dy > 0 ? y + r : dy < 0 ? y - r - bh : y - bh / 2;
        const box = { x0, y0, x1: x0 + bw, y1: y0 + bh };
        if (this.inside(box) && this.free(box, this.obstacles)) return box;
      }
    }
    return this.nearest(x, y, bw, bh, this.obstacles) ?? this.nearest(x, y, bw, bh, []);
  }

  /** The free box of size bw × bh on a grid over the canvas whose nearest point is closest to (x, y). */
  nearest(x, y, bw, bh, obstacles) {
    let best = null, bestDistance = Infinity;
    for (let y0 = 0; y0 + bh <= this.height; y0 += SCAN_STEP) {
      for (let x0 = 0; x0 + bw <= this.width; x0 += SCAN_STEP) {
        const box = { x0, y0, x1: x0 + bw, y1: y0 + bh };
        const distance = Math.hypot(x - clamp(x, box.x0, box.x1), y - clamp(y, box.y0, box.y1));
        if (distance < bestDistance && this.free(box, obstacles)) [best, bestDistance] = [box, distance];
      }
    }
    return best;
  }

  inside(box) {
    return box.x0 >= 0 && box.y0 >= 0 && box.x1 <= this.width && box.y1 <= this.height;
  }

  /** Whether `box` is clear of every label placed and every one of `obstacles`. */
  free(box, obstacles) {
    return !this.placed.some((b) => overlaps(b, box)) && !obstacles.some((b) => overlaps(b, box));
  }
}

/** Whether two boxes share any area. */
function overlaps(a, b) {
  return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
}

function clamp(v, lo, hi) {
  return Math.min(hi, Math.max(lo, v));
}
