//! Where one clip can cut to another: the windowed, aligned frame distance D(f, t) of
//! Kovar et al. 2002, and its local minima under a threshold.

use super::alignment::Moments;
use super::Clip;

/// A candidate cut: after frame `from` of clip `from_clip`, play frame `to` of `to_clip`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Transition {
    pub(crate) from_clip: usize,
    pub(crate) from: usize,
    pub(crate) to_clip: usize,
    pub(crate) to: usize,
    /// RMS joint distance over the window after alignment, in metres.
    pub(crate) rms_m: f64,
}

/// Finds every transition between (and within) `clips` whose windowed distance is a
/// local minimum below `threshold_m` (RMS joint distance in metres).
///
/// D compares the `window` frames that would follow the cut in the source (from + 1 …)
/// with the `window` frames that start at the target, all joints weighted equally, after
/// the ground alignment that best matches them. Clips should come from one subject (the
/// caller compares a behaviour's clips only, and each behaviour is one CMU subject), so
/// skeleton size never masquerades as a pose difference.
pub(super) fn find(clips: &[&Clip], window: usize, threshold_m: f64) -> Vec<Transition> {
    find_windows(clips, &[window], threshold_m)
        .pop()
        .unwrap_or_default()
}

/// [`find`] for several windows at once, one list per window in the order given: the
/// per-frame cross sums (frames² × joints per pair of clips, most of the work) do not
/// depend on the window, so they are computed once and summed along diagonals into
/// windows of each length.
///
/// A mirrored clip's transitions are its original's, mirrored: the aligned distance
/// between two windows does not change when both are reflected (a reflection is a rigid
/// motion of space, and it turns the best rotation about the vertical into its
/// reverse), so the transitions from a mirror image to any clip are those from its
/// original to that clip's twin. They are copied rather than computed, which halves the
/// work and keeps the graph exactly symmetric, where computing them would break ties
/// in the local minima by rounding.
pub(super) fn find_windows(
    clips: &[&Clip],
    windows: &[usize],
    threshold_m: f64,
) -> Vec<Vec<Transition>> {
    let twins = mirror_twins(clips);
    let mut found = vec![Vec::new(); windows.len()];
    for (ca, a) in clips.iter().enumerate() {
        if a.is_mirror() && twins[ca].is_some() {
            continue;
        }
        for (cb, b) in clips.iter().enumerate() {
            let Some(cross) = Cross::of(a, b) else {
                continue;
            };
            for (w, &window) in windows.iter().enumerate() {
                cross.minima(a, b, window, threshold_m, |from, to, rms_m| {
                    // A cut to (nearly) the very next frames is the clip itself.
                    let trivial = ca == cb && to.abs_diff(from + 1) <= window;
                    if !trivial {
                        found[w].push(Transition {
                            from_clip: ca,
                            from,
                            to_clip: cb,
                            to,
                            rms_m,
                        });
                    }
                });
            }
        }
    }
    for list in &mut found {
        let mirrored: Vec<Transition> = list
            .iter()
            .filter_map(|t| {
                Some(Transition {
                    from_clip: twins[t.from_clip]?,
                    to_clip: twins[t.to_clip]?,
                    ..*t
                })
            })
            .collect();
        list.extend(mirrored);
        list.sort_by_key(|t| (t.from_clip, t.from, t.to_clip, t.to));
    }
    found
}

/// Each clip's mirror image among `clips` (by name), if there.
fn mirror_twins(clips: &[&Clip]) -> Vec<Option<usize>> {
    clips
        .iter()
        .map(|c| {
            let twin = c.mirror_name();
            clips.iter().position(|o| o.name == twin)
        })
        .collect()
}

/// Per-frame sums over joints of one frame: Σx, Σz, Σ|p|².
#[derive(Clone, Copy, Default)]
struct FrameSums {
    x: f64,
    z: f64,
    norm: f64,
}

fn window_sums(clip: &Clip, window: usize) -> Vec<FrameSums> {
    let per_frame: Vec<FrameSums> = (0..clip.frame_count())
        .map(|f| {
            clip.frame(f)
                .iter()
                .fold(FrameSums::default(), |s, p| FrameSums {
                    x: s.x + p.x,
                    z: s.z + p.z,
                    norm: s.norm + p.length_squared(),
                })
        })
        .collect();
    per_frame
        .windows(window)
        .map(|w| {
            w.iter().fold(FrameSums::default(), |s, f| FrameSums {
                x: s.x + f.x,
                z: s.z + f.z,
                norm: s.norm + f.norm,
            })
        })
        .collect()
}

/// Cross sums of the frame pairs of two clips, Σ(x x′ + z z′), Σ(x z′ − x′ z), Σ y y′
/// over joints, accumulated along each diagonal (frame pairs (fa, fb), (fa − 1, fb − 1),
/// …), so the sum over any window of pairs is one difference whatever its length.
struct Cross {
    lb: usize,
    diagonal: Vec<[f64; 3]>,
}

impl Cross {
    fn of(a: &Clip, b: &Clip) -> Option<Cross> {
        let (la, lb) = (a.frame_count(), b.frame_count());
        if a.joint_count() != b.joint_count() {
            return None;
        }
        let mut sums = vec![[0.0f64; 3]; la * lb];
        for fa in 0..la {
            let pa = a.frame(fa);
            for fb in 0..lb {
                let pb = b.frame(fb);
                let mut c = [0.0; 3];
                for (p, q) in pa.iter().zip(pb) {
                    c[0] += p.x * q.x + p.z * q.z;
                    c[1] += p.x * q.z - q.x * p.z;
                    c[2] += p.y * q.y;
                }
                if fa > 0 && fb > 0 {
                    let before = sums[(fa - 1) * lb + fb - 1];
                    c = [c[0] + before[0], c[1] + before[1], c[2] + before[2]];
                }
                sums[fa * lb + fb] = c;
            }
        }
        Some(Cross { lb, diagonal: sums })
    }

    /// The cross sums over the `window` frame pairs starting at (sa, sb).
    fn window(&self, sa: usize, sb: usize, window: usize) -> [f64; 3] {
        let lb = self.lb;
        let end = self.diagonal[(sa + window - 1) * lb + sb + window - 1];
        if sa == 0 || sb == 0 {
            return end;
        }
        let before = self.diagonal[(sa - 1) * lb + sb - 1];
        [end[0] - before[0], end[1] - before[1], end[2] - before[2]]
    }

    /// Emits (from, to, rms) for every local minimum of D below `threshold_m`.
    fn minima(
        &self,
        a: &Clip,
        b: &Clip,
        window: usize,
        threshold_m: f64,
        mut emit: impl FnMut(usize, usize, f64),
    ) {
        let (la, lb, joints) = (a.frame_count(), self.lb, a.joint_count());
        // Windows start at s_a = from + 1 in a and s_b = to in b.
        if window == 0 || la < window + 1 || lb < window {
            return;
        }
        let (wa, wb) = (window_sums(a, window), window_sums(b, window));
        let (na, nb) = (la - window + 1, lb - window + 1);
        // D over every (s_a, s_b), s_a ≥ 1; NaN marks "no window here".
        let mut d = vec![f64::NAN; na * nb];
        let weight = (window * joints) as f64;
        for sa in 1..na {
            for sb in 0..nb {
                let m = Moments::from_sums(
                    weight,
                    [wa[sa].x, wa[sa].z, wa[sa].norm],
                    [wb[sb].x, wb[sb].z, wb[sb].norm],
                    self.window(sa, sb, window),
                );
                // Rounding in the diagonal differences can take a perfect match a hair
                // below zero.
                d[sa * nb + sb] = (m.aligned_distance() / weight).max(0.0).sqrt();
            }
        }
        let at = |sa: usize, sb: usize| d[sa * nb + sb];
        for sa in 1..na {
            for sb in 0..nb {
                let v = at(sa, sb);
                if v.is_nan() || v >= threshold_m {
                    continue;
                }
                let is_minimum = (sa.saturating_sub(1)..=(sa + 1).min(na - 1))
                    .flat_map(|i| {
                        (sb.saturating_sub(1)..=(sb + 1).min(nb - 1)).map(move |j| (i, j))
                    })
                    .all(|(i, j)| (i, j) == (sa, sb) || at(i, j).is_nan() || v <= at(i, j));
                if is_minimum {
                    emit(sa - 1, sb, v);
                }
            }
        }
    }
}
