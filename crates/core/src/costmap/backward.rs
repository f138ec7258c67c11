//! `search` without obstacles: cost-to-go maps per branch node of the compressed graph,
//! composed backward with each segment's rigid motion.
//!
//! Root motion is relative: what a body can reach from a node depends on where it stands
//! and faces only through a rotation and a translation. So for every branch node n we
//! compute V_n(x), the frames needed to reach the point x *in n's own frame*, by the
//! Bellman equation over the segments s leaving n (to m, taking f_s frames, ending at
//! pose T_s in n's frame):
//!
//! ```text
//!     V_n(x) = min( frames at which s itself passes x,   f_s + V_m(T_s⁻¹ x) )
//! ```
//!
//! solved once for all nodes with a bucket queue in order of frames (a uniform-cost
//! search run backward: settling V_m(y) offers f_s + V_m(y) to V_n at T_s(y)). The map
//! is then V at the start pose. Unlike a forward search there is no heading to
//! discretise, which is what made forward states merge badly. Each state keeps the exact
//! point whose walk set its value, so every cost is that of a real walk (its path replays
//! exactly); the one approximation is that a local cell (a third of a map cell) keeps
//! only its cheapest walk, so a later walk through another point of the same cell is not
//! followed. Near the start nothing is merged: the walks through the first
//! [`EXACT_LEVELS`] choices are followed exactly, and every walk offered to the node one
//! of them ends at is placed in the map through it as it comes (not only those that
//! improve a local cell), so a walk that grazes a map cell is not lost to a cheaper one
//! elsewhere in the same local cell. And every walk short enough to count (about 28
//! frames on CMU running; see [`exhaustive_horizon`]) is followed exactly from the start,
//! so the cells reachable that soon get their exact costs.

use super::grid::cell_index;
use super::prepared::{Prepared, Segments};
use super::Grid;
use crate::motion::Walker;
use glam::DVec2;

/// One segment of the compressed graph, walked once from the origin.
struct Segment {
    from: u32,
    to: u32,
    frames: u32,
    /// The pose at its end, in its start's frame.
    end: Walker,
    /// Where the root is after each frame, with the frames taken so far.
    stops: Vec<(DVec2, u32)>,
    /// Its steps, as [`Segments::step`] numbers.
    first_step: usize,
}

/// The square grid V lives on, centred on the node.
struct LocalGrid {
    cell: f64,
    half: f64,
    n: usize,
}

impl LocalGrid {
    fn index(&self, p: DVec2) -> Option<usize> {
        cell_index((p + DVec2::splat(self.half)) / self.cell, self.n)
    }
}

/// How a state got its value: along `segment`, then on from state `next`; or, with the
/// top bit of `next` set, the segment's own first `next & !BASE` steps passed the point.
#[derive(Clone, Copy)]
struct Via {
    segment: u32,
    next: u32,
}

const BASE: u32 = 1 << 31;
/// Local cells per map cell side: finer is closer to exhaustive and slower (time grows
/// about with the square; BENCHMARKS.md has the trade-off measured on `run`).
const LOCAL_CELLS_PER_MAP_CELL: f64 = 3.0;
/// Most (branch node, local cell) states search may hold: 18 bytes each, so about
/// 150 MB.
const STATE_BUDGET: usize = 8_000_000;

pub(crate) struct BackwardResult {
    pub costs: Vec<Option<u32>>,
    pub paths: Vec<Vec<u32>>,
}

/// The maps from each of `starts` (nodes of the graph), from one backward pass: the
/// cost-to-go of every branch node does not depend on where a walk began, so several
/// start states cost one pass plus their own exact walks.
pub(crate) fn build(
    grid: &Grid,
    graph: &Prepared,
    nodes: usize,
    depth: u32,
    starts: &[u32],
) -> Vec<BackwardResult> {
    let segs = graph.segments(nodes, false);
    let segments = walk_segments(graph, &segs, nodes);
    let branch_count = (0..nodes).filter(|&n| segs.branch[n]).count().max(1);
    let local = {
        // As far as a point of the map can be from a body that is still on it. Not
        // narrowed to what `depth` frames can reach: the local cells, and so which walks
        // merge, must not depend on the horizon, or a longer horizon could merge a walk
        // a shorter one kept and make a cell dearer.
        let half = grid.size_m + grid.cell_m;
        // A densely connected graph (thousands of branch nodes) would need gigabytes at
        // full resolution: coarsen the local cells to keep within the state budget
        // rather than exhaust memory.
        let budget_cell = 2.0 * half * (branch_count as f64 / STATE_BUDGET as f64).sqrt();
        let cell = (grid.cell_m / LOCAL_CELLS_PER_MAP_CELL).max(budget_cell);
        LocalGrid {
            cell,
            half,
            n: (2.0 * half / cell).ceil() as usize,
        }
    };
    let per_node = local.n * local.n;
    let branch_ids: Vec<Option<u32>> = {
        let mut next = 0;
        (0..nodes)
            .map(|n| {
                segs.branch[n].then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect()
    };
    let node_of_branch: Vec<u32> = (0..nodes as u32)
        .filter(|&n| segs.branch[n as usize])
        .collect();
    let branches = node_of_branch.len();
    // Frames fit in 16 bits (depth is at most 10,000), points in two f32s: millions of
    // states, so their size matters.
    let depth = depth.min(u32::from(u16::MAX) - 1);
    let mut value = vec![u16::MAX; branches * per_node];
    // The exact point (in the node's frame) whose walk set the state's value.
    let mut point = vec![[0f32; 2]; branches * per_node];
    let mut via = vec![
        Via {
            segment: u32::MAX,
            next: u32::MAX
        };
        branches * per_node
    ];
    // A value at node n only matters if a start reaches n with that many frames to
    // spare: an exact bound that skips most of the plane of nodes far from the starts.
    let mut spare = vec![0u32; nodes];
    for &start in starts {
        for (n, f) in frames_from(graph, start, nodes).into_iter().enumerate() {
            spare[n] = spare[n].max(depth.saturating_sub(f.unwrap_or(u32::MAX)));
        }
    }
    let mut costs = vec![vec![None; grid.cells()]; starts.len()];
    let mut paths = vec![vec![Vec::new(); grid.cells()]; starts.len()];
    let mut chains: Vec<(usize, Chain)> = Vec::new();
    for (k, &start) in starts.iter().enumerate() {
        if let Some(c) = grid.cell_of(Walker::START.position) {
            costs[k][c] = Some(0);
        }
        // Every short walk, exactly. That includes the lead from the start node to the
        // first branch node (a single walk, so always within the horizon) and places its
        // cells.
        let horizon = exhaustive_horizon(graph, start, nodes, depth);
        exhaust(graph, grid, start, horizon, &mut costs[k], &mut paths[k]);
        // The lead, where the exact walks through the first choices begin.
        let mut lead = Vec::new();
        let (mut node, mut at, mut frames) = (start, Walker::START, 0u32);
        while !segs.branch[node as usize] && frames < depth {
            let Some(e) = graph.out(node).first() else {
                break;
            };
            at = at.after(&e.step, e.turn);
            frames += e.frames;
            node = e.to;
            lead.push(e.id);
        }
        // Every walk offered to a node near the start is placed in the map as it is
        // offered, through every exact walk from the start to that node, whether or not
        // it improves the node's local cell: the local cell keeps one walk, but the map
        // wants the cheapest in each of *its* cells, and a walk that only grazes a map
        // cell must not lose to a cheaper one elsewhere in the same local cell.
        if segs.branch[node as usize] {
            let root = Chain {
                node,
                at,
                frames,
                edges: lead,
                level: 0,
            };
            chains.extend(
                chains_from(graph, &segs, &segments, root)
                    .into_iter()
                    .map(|c| (k, c)),
            );
        }
    }
    let mut chains_at: Vec<Vec<u32>> = vec![Vec::new(); nodes];
    for (i, (_, c)) in chains.iter().enumerate() {
        chains_at[c.node as usize].push(i as u32);
    }
    // Cheapest first, so placing an offer stops at the first chain it would take past
    // the horizon.
    for at_node in &mut chains_at {
        at_node.sort_by_key(|&i| chains[i as usize].1.frames);
    }
    let shallow_at: Vec<Vec<u32>> = chains_at
        .iter()
        .map(|at_node| {
            at_node
                .iter()
                .copied()
                .filter(|&i| chains[i as usize].1.level <= FAR_LEVELS)
                .collect()
        })
        .collect();
    let mut placed: Vec<Vec<Option<(u32, u32, Via)>>> =
        vec![vec![None; grid.cells()]; starts.len()];
    // Places an offer through each chain to its node, cheapest chain first, until the
    // horizon.
    let mut place = |node: u32, local_point: DVec2, offered: u32, how: Via| {
        let through = if offered > NEAR_OFFER_FRAMES {
            &shallow_at[node as usize]
        } else {
            &chains_at[node as usize]
        };
        for &chain in through {
            let (k, from) = &chains[chain as usize];
            let total = from.frames + offered;
            if total > depth {
                break;
            }
            let world = from.at.position + local_point.rotate(from.at.facing);
            if let Some(c) = grid.cell_of(world) {
                if costs[*k][c].is_none_or(|v| total < v)
                    && placed[*k][c].is_none_or(|(v, _, _)| total < v)
                {
                    placed[*k][c] = Some((total, chain, how));
                }
            }
        }
    };
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); depth as usize + 1];
    let mut into: Vec<Vec<u32>> = vec![Vec::new(); nodes];
    for (s, seg) in segments.iter().enumerate() {
        let base = branch_ids[seg.from as usize].expect("segments start at branch nodes") as usize
            * per_node;
        for (k, &(p, frames)) in seg.stops.iter().enumerate() {
            let Some(cell) = local.index(p) else { break };
            let state = base + cell;
            let how = Via {
                segment: s as u32,
                next: BASE | (k as u32 + 1),
            };
            place(seg.from, p, frames, how);
            if frames <= spare[seg.from as usize] && frames < u32::from(value[state]) {
                value[state] = frames as u16;
                point[state] = p.as_vec2().to_array();
                via[state] = how;
                buckets[frames as usize].push(state as u32);
            }
        }
        into[seg.to as usize].push(s as u32);
    }
    for t in 0..=depth as usize {
        for state in std::mem::take(&mut buckets[t]) {
            let state = state as usize;
            if value[state] as usize != t {
                continue; // settled earlier at a lower value
            }
            let (m_branch, y) = (
                state / per_node,
                DVec2::new(f64::from(point[state][0]), f64::from(point[state][1])),
            );
            let m = node_of_branch[m_branch];
            for &s in &into[m as usize] {
                let seg = &segments[s as usize];
                let offered = t as u32 + seg.frames;
                if offered > spare[seg.from as usize] {
                    continue;
                }
                let x = seg.end.position + y.rotate(seg.end.facing);
                let how = Via {
                    segment: s,
                    next: state as u32,
                };
                place(seg.from, x, offered, how);
                let Some(cell) = local.index(x) else { continue };
                let target =
                    branch_ids[seg.from as usize].expect("branch") as usize * per_node + cell;
                if offered < u32::from(value[target]) {
                    value[target] = offered as u16;
                    point[target] = x.as_vec2().to_array();
                    via[target] = how;
                    buckets[offered as usize].push(target as u32);
                }
            }
        }
    }

    let mut results = Vec::with_capacity(starts.len());
    for (k, (mut costs, mut paths)) in costs.into_iter().zip(paths).enumerate() {
        // Each placed walk is replayed and kept in the cell it really ends in: the point
        // a state keeps is stored in single precision, and a walk that ends on a cell's
        // edge (as a straight run along an axis does) may land on the other side of it.
        let mut found: Vec<(usize, u32, Vec<u32>)> = Vec::new();
        for entry in placed[k].iter().flatten() {
            let &(total, chain, how) = entry;
            let lead = &chains[chain as usize].1;
            let mut at = lead.at;
            let mut path = lead.edges.clone();
            let mut v = how;
            loop {
                let seg = &segments[v.segment as usize];
                let len = if v.next & BASE != 0 {
                    (v.next & !BASE) as usize
                } else {
                    seg.stops.len()
                };
                for step in 0..len {
                    let e = graph.edge(segs.step(seg.first_step + step));
                    at = at.after(&e.step, e.turn);
                    path.push(e.id);
                }
                if v.next & BASE != 0 {
                    break;
                }
                v = via[v.next as usize];
            }
            if let Some(c) = grid.cell_of(at.position) {
                found.push((c, total, path));
            }
        }
        for (c, total, path) in found {
            if costs[c].is_none_or(|v| total < v) {
                costs[c] = Some(total);
                paths[c] = path;
            }
        }
        results.push(BackwardResult { costs, paths });
    }
    results
}

/// Branch levels from the start walked exactly (every choice followed, nothing merged)
/// before the search's merged values take over. Walks near the start are few and their
/// cells are reached by few of them, so a merge there costs most (a walk that grazes a
/// cell by millimetres is the one that reaches it first). Each level multiplies the
/// exact walks by about 1.8 on CMU running; measured there against 200,000 Monte Carlo
/// walks (as good in this share of cells, time): 0 levels 89.5 % 59 ms, 6 levels 94.0 %
/// 74 ms, 8 levels 95.3 % 106 ms, 10 levels 96.3 % 0.20 s, 16 levels 99.0 % 6.7 s.
const EXACT_LEVELS: usize = 6;

/// An offer of more frames than this is placed only through the exact walks of at most
/// [`FAR_LEVELS`] choices: the exact walks exist for the cells near the start, where a
/// grazing walk decides a cell, and placing every long walk through every one of them
/// was half of search's time.
const NEAR_OFFER_FRAMES: u32 = 60;
const FAR_LEVELS: u8 = 2;

/// The most exact walks kept: levels stop before they would pass it. (CMU running has
/// 107 at six levels; a graph with thousands of branch nodes would have hundreds of
/// thousands.)
const CHAIN_BUDGET: usize = 400;

/// An exact walk from the start to a branch node: where it stands on arriving (in the
/// start's frame), after how many frames, by which edges.
struct Chain {
    node: u32,
    at: Walker,
    frames: u32,
    edges: Vec<u32>,
    /// Choices made since the lead (0 for the lead itself).
    level: u8,
}

/// Every walk from the start through the first [`EXACT_LEVELS`] choices: from `root`
/// (the lead to the first branch node), each segment in turn.
fn chains_from(graph: &Prepared, segs: &Segments, segments: &[Segment], root: Chain) -> Vec<Chain> {
    let mut out_of: Vec<Vec<usize>> = vec![Vec::new(); segs.branch.len()];
    for (i, s) in segments.iter().enumerate() {
        out_of[s.from as usize].push(i);
    }
    let mut chains = vec![root];
    let mut level = 0..1;
    // Levels are counted whatever the horizon, so the same walks are exact at any depth
    // (a chain past the horizon places nothing: offers stop at the first chain too long).
    for _ in 0..EXACT_LEVELS {
        // Each offer is placed through every chain to its node: on a densely connected
        // graph the chains of the next level would cost more than they find.
        let coming: usize = level
            .clone()
            .map(|i| out_of[chains[i].node as usize].len())
            .sum();
        if chains.len() + coming > CHAIN_BUDGET {
            break;
        }
        let next = chains.len();
        for i in level.clone() {
            for &s in &out_of[chains[i].node as usize] {
                let seg = &segments[s];
                let from = &chains[i];
                let frames = from.frames + seg.frames;
                let mut at = from.at;
                let mut edges = from.edges.clone();
                for k in 0..seg.stops.len() {
                    let e = graph.edge(segs.step(seg.first_step + k));
                    at = at.after(&e.step, e.turn);
                    edges.push(e.id);
                }
                chains.push(Chain {
                    node: seg.to,
                    at,
                    frames,
                    edges,
                    level: from.level + 1,
                });
            }
        }
        level = next..chains.len();
    }
    chains
}

/// Most walker steps the exhaustive walks from the start may take: about 4 ms.
const EXHAUSTIVE_STEPS: f64 = 200_000.0;

/// The longest horizon (in frames, at most `depth`) within which every walk from `start`
/// fits in [`EXHAUSTIVE_STEPS`] steps, counted without walking them: the number of walks
/// of each length, by dynamic programming over the nodes. On CMU running that is 28
/// frames, 7 with its mirror images; a densely connected graph gets a shorter one.
pub(crate) fn exhaustive_horizon(graph: &Prepared, start: u32, nodes: usize, depth: u32) -> u32 {
    // Walks ending at frame t, by node, for the frames an edge can still reach: a ring
    // of rows, so a long horizon costs no more memory than a short one.
    let longest = (0..graph.edge_count())
        .map(|i| graph.edge(i).frames as usize)
        .max()
        .unwrap_or(1);
    let mut ways = vec![vec![0f64; nodes]; longest + 1];
    ways[0][start as usize] = 1.0;
    let mut steps = 0.0;
    for t in 0..depth as usize {
        let now = std::mem::replace(&mut ways[t % (longest + 1)], vec![0f64; nodes]);
        for (n, &w) in now.iter().enumerate().filter(|(_, &w)| w > 0.0) {
            for e in graph.out(n as u32) {
                ways[(t + e.frames as usize) % (longest + 1)][e.to as usize] += w;
            }
        }
        steps += ways[(t + 1) % (longest + 1)].iter().sum::<f64>();
        if steps > EXHAUSTIVE_STEPS {
            return t as u32;
        }
    }
    depth
}

/// Where a walk is: its node, its pose in the start's frame, the frames it has taken.
#[derive(Clone, Copy)]
struct Walk {
    node: u32,
    at: Walker,
    frames: u32,
}

/// Follows every walk from `start` up to `horizon` frames, depth first, and keeps in the
/// map each cell's cheapest, with its path. Merged search loses cells that the best walk
/// enters by millimetres (a sway of the hips across a cell's edge); within the horizon
/// nothing is merged, so every cell reachable that soon gets its exact cost. Monte
/// Carlo's random walks cover nearly every walk this short, so this is where it would
/// otherwise win. (An explicit stack: a graph with few choices can have a horizon of
/// thousands of frames.)
fn exhaust(
    graph: &Prepared,
    grid: &super::Grid,
    start: u32,
    horizon: u32,
    costs: &mut [Option<u32>],
    paths: &mut [Vec<u32>],
) {
    let root = Walk {
        node: start,
        at: Walker::START,
        frames: 0,
    };
    // Each walk on the stack with the next of its edges to try; `trail` holds the edges
    // taken to the top one.
    let mut stack = vec![(root, 0)];
    let mut trail = Vec::new();
    while let Some((walk, tried)) = stack.last_mut() {
        let Some(e) = graph.out(walk.node).get(*tried) else {
            stack.pop();
            trail.pop();
            continue;
        };
        *tried += 1;
        let next = Walk {
            node: e.to,
            at: walk.at.after(&e.step, e.turn),
            frames: walk.frames + e.frames,
        };
        if next.frames > horizon {
            continue;
        }
        trail.push(e.id);
        if let Some(c) = grid.cell_of(next.at.position) {
            if costs[c].is_none_or(|v| next.frames < v) {
                costs[c] = Some(next.frames);
                paths[c].clone_from(&trail);
            }
        }
        stack.push((next, 0));
    }
}

/// The fewest frames from `start` to each node (Dijkstra over the enabled edges).
fn frames_from(graph: &Prepared, start: u32, nodes: usize) -> Vec<Option<u32>> {
    let mut best = vec![None; nodes];
    let mut queue = std::collections::BinaryHeap::new();
    best[start as usize] = Some(0);
    queue.push(std::cmp::Reverse((0u32, start)));
    while let Some(std::cmp::Reverse((f, n))) = queue.pop() {
        if best[n as usize] != Some(f) {
            continue;
        }
        for e in graph.out(n) {
            let g = f + e.frames;
            if best[e.to as usize].is_none_or(|b| g < b) {
                best[e.to as usize] = Some(g);
                queue.push(std::cmp::Reverse((g, e.to)));
            }
        }
    }
    best
}

fn walk_segments(graph: &Prepared, segs: &Segments, nodes: usize) -> Vec<Segment> {
    let mut out = Vec::new();
    for n in 0..nodes as u32 {
        for (first, len, to) in segs.out(n) {
            let mut at = Walker::START;
            let mut frames = 0;
            let mut stops = Vec::with_capacity(len);
            for k in 0..len {
                let e = graph.edge(segs.step(first + k));
                at = at.after(&e.step, e.turn);
                frames += e.frames;
                stops.push((at.position, frames));
            }
            out.push(Segment {
                from: n,
                to,
                frames,
                end: at,
                stops,
                first_step: first,
            });
        }
    }
    out
}
