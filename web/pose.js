// Posing bodies from motion capture, as the server plays it (PROTOCOL.md, "the pose"):
// a basketball player's frame names a motion-graph node and, across a cut, a blend
// [from, weight]; the joints of every node come once from GET /api/motion/{behaviour}
// (a library). A fielder has no graph: it runs a stride loop of the run capture chosen
// by its speed, its phase set by the distance it has run, so a planted foot stays
// planted (up to the loop's stated foot_slide_m) at any speed. Pure functions: the 3-D
// view draws what these return, and the browser test checks them against the poses.

/** The behaviours' pose libraries, fetched once per page (the browser revalidates). */
const libraries = new Map();

/** The pose library of `behaviour`, from the server (a promise, shared). */
export function library(behaviour) {
  if (!libraries.has(behaviour)) {
    libraries.set(behaviour, fetch(`/api/motion/${encodeURIComponent(behaviour)}`).then((r) => {
      if (!r.ok) throw new Error(`GET /api/motion/${behaviour}: ${r.status}`);
      return r.json();
    }));
  }
  return libraries.get(behaviour);
}

/**
 * The world joints [[x, y, z], …] of a body showing `node` of `lib` (blended from
 * `blend[0]` with weight `blend[1]` of `node`, if given), root at `position` [x, z],
 * facing `heading` (radians from +x toward +z).
 */
export function posePlayer(lib, node, blend, position, heading) {
  const to = lib.poses_mm[node ?? lib.standing] ?? lib.poses_mm[lib.standing];
  const from = blend ? lib.poses_mm[blend[0]] : null;
  const w = from ? Number(blend[1]) : 1;
  const local = new Array(to.length);
  for (let i = 0; i < to.length; i++) local[i] = (from ? from[i] + w * (to[i] - from[i]) : to[i]) / 1000;
  return place(local, position, heading);
}

/** Local joints (flat, metres, facing +x) turned by `heading` and moved to `position`. */
function place(local, [px, pz], heading) {
  const c = Math.cos(heading), s = Math.sin(heading);
  const out = [];
  for (let i = 0; i < local.length; i += 3) {
    const x = local[i], y = local[i + 1], z = local[i + 2];
    out.push([px + x * c - z * s, y, pz + x * s + z * c]);
  }
  return out;
}

/** Below this speed, m/s, a fielder stands rather than runs. */
export const STANDING_M_S = 0.4;

/** The stride loop of `lib` nearest `speed` m/s, or null to stand. */
export function strideFor(lib, speed) {
  if (!(speed >= STANDING_M_S) || !lib.strides.length) return null;
  return lib.strides.reduce((a, b) => (Math.abs(b.speed_m_s - speed) < Math.abs(a.speed_m_s - speed) ? b : a));
}

/**
 * A fielder's world joints: standing, or running the loop for its `speed` at the phase
 * `distance` (m run so far) gives, at `position` facing `heading`.
 */
export function poseRunner(lib, speed, distance, position, heading) {
  const stride = strideFor(lib, speed);
  if (!stride) return posePlayer(lib, lib.standing, null, position, heading);
  const n = stride.nodes.length;
  const x = (((distance / stride.length_m) % 1) + 1) % 1 * n;
  const k = Math.min(n - 1, Math.floor(x));
  return posePlayer(lib, stride.nodes[(k + 1) % n], [stride.nodes[k], x - k], position, heading);
}

/** The bones of a library's skeleton: [joint, parent] pairs. */
export function bones(lib) {
  const out = [];
  lib.parents.forEach((p, j) => { if (p !== null && p !== undefined) out.push([j, p]); });
  return out;
}
