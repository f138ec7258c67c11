//! A hand-written reader for Acclaim motion (AMC), CMU's native motion format: per frame,
//! its number on a line of its own, then one line per bone, the bone's name and its
//! values in the order its skeleton (`asf`) lists its degrees of freedom.
//!
//! Read against its skeleton, strictly: frames are numbered one by one, every bone with
//! values appears exactly once in every frame with exactly as many values as its dofs,
//! and every value is a finite number, or the file is refused at the line that breaks
//! the rule. Angles are not range-checked, like BVH's: real captures have the odd glitch
//! spike, and root angles run past ±360° (CMU does not wrap them). Only the root's
//! position is, to a distance no capture comes near, so no position can overflow. Bounded: lines are
//! capped as in `asf`, and so is the number of frames (by [`MAX_JOINT_FRAMES`]), so a
//! short hostile file cannot make forward kinematics allocate without limit.
//!
//! Unlike BVH, an AMC file has no reference pose (every frame is captured movement) and
//! need not state its frame rate: CMU captures at 120 Hz and writes no rate, so that is
//! the rate unless a `:SAMPLES-PER-SECOND` header gives one.

use super::asf::{
    number, shown, unexpected, AngleUnit, Lines, ParseError, ParseErrorKind, RootChannel, Skeleton,
};
use std::collections::BTreeMap;

/// The rate CMU captured at, Hz: its AMC files do not say.
pub(super) const CMU_FRAME_RATE: f64 = 120.0;
/// The most frames × joints a file may hold: 135,000 frames of CMU's 31 joints (19
/// minutes at 120 Hz; CMU's longest trials last a few minutes). The positions forward
/// kinematics makes of them take at most 100 MB.
pub(super) const MAX_JOINT_FRAMES: usize = 1 << 22;
/// The farthest the root may stand from the origin, in file units (56 km in CMU's): a
/// capture volume is metres across. Beyond some 1e307, sums and interpolation of
/// positions would overflow to infinity.
const MAX_TRANSLATION: f64 = 1e6;
/// Capture runs at 1 Hz to 10 kHz, as for BVH's frame time.
const SAMPLE_RATES: std::ops::RangeInclusive<f64> = 1.0..=10_000.0;

/// A parsed AMC file: every frame's values in the skeleton's order.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Motion {
    /// Frames per second: the file's `:SAMPLES-PER-SECOND`, else [`CMU_FRAME_RATE`].
    pub frame_rate: f64,
    /// Frame-major. A frame holds the root's values in `:root order`, then each bone's in
    /// its dof order, bones in [`Skeleton::bones`] order. Angles are in radians,
    /// translations in file units.
    values: Vec<f64>,
    channels_per_frame: usize,
    frames: usize,
}

impl Motion {
    pub(super) fn frame_count(&self) -> usize {
        self.frames
    }

    pub(super) fn frame(&self, f: usize) -> &[f64] {
        let n = self.channels_per_frame;
        &self.values[f * n..(f + 1) * n]
    }
}

/// One line's worth of a frame: the root (slot 0) or a bone (slot b + 1).
struct Slot<'a> {
    name: &'a str,
    /// Where its values start in a frame, and how many it has.
    offset: usize,
    count: usize,
    /// Per value, whether it is an angle (converted to radians) or a translation.
    angles: Vec<bool>,
}

/// Reads a whole AMC file against `skeleton`.
pub(super) fn parse(text: &str, skeleton: &Skeleton) -> Result<Motion, ParseError> {
    let mut slots = vec![Slot {
        name: "root",
        offset: 0,
        count: skeleton.root.len(),
        angles: skeleton
            .root
            .iter()
            .map(|c| matches!(c, RootChannel::Rotation(_)))
            .collect(),
    }];
    for bone in &skeleton.bones {
        let offset = slots.last().map_or(0, |s| s.offset + s.count);
        slots.push(Slot {
            name: &bone.name,
            offset,
            count: bone.dofs.len(),
            angles: vec![true; bone.dofs.len()],
        });
    }
    let channels_per_frame = slots.last().map_or(0, |s| s.offset + s.count);
    let by_name: BTreeMap<&str, usize> =
        slots.iter().enumerate().map(|(i, s)| (s.name, i)).collect();
    let max_frames = MAX_JOINT_FRAMES / slots.len();

    let mut lines = Lines::new(text);
    let (frame_rate, angle_unit) = header(&mut lines, skeleton.angle_unit)?;

    let mut values = Vec::new();
    let mut current = vec![0.0; channels_per_frame];
    let mut given = vec![false; slots.len()];
    let mut frames = 0;
    // The frame being read: its line and number.
    let mut frame: Option<(usize, u64)> = None;
    while let Some((line, tokens)) = lines.next()? {
        if let [text] = tokens[..] {
            if text.bytes().all(|b| b.is_ascii_digit()) {
                let expected = frame.map(|(_, n)| n + 1);
                let number = text
                    .parse::<u64>()
                    .ok()
                    .filter(|&n| expected.is_none_or(|e| n == e));
                let Some(number) = number else {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::FrameNumber {
                            expected: expected.unwrap_or(1),
                            found: shown(text),
                        },
                    });
                };
                if let Some(done) = frame {
                    complete(done, &slots, &given)?;
                    values.extend_from_slice(&current);
                }
                if frames == max_frames {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::TooManyFrames {
                            max: max_frames,
                            joints: slots.len(),
                        },
                    });
                }
                given.fill(false);
                frames += 1;
                frame = Some((line, number));
                continue;
            }
        }
        if frame.is_none() {
            return Err(unexpected(line, "a frame number", tokens[0]));
        }
        let name = tokens[0];
        let slot = *by_name.get(name).ok_or_else(|| ParseError {
            line,
            kind: ParseErrorKind::UnknownBone(shown(name)),
        })?;
        if std::mem::replace(&mut given[slot], true) {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::Repeated(format!("`{}` in one frame", shown(name))),
            });
        }
        let s = &slots[slot];
        let texts = &tokens[1..];
        if texts.len() != s.count {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::ValueCount {
                    bone: shown(name),
                    expected: s.count,
                    found: texts.len(),
                },
            });
        }
        for (k, (text, &angle)) in texts.iter().zip(&s.angles).enumerate() {
            let v = number(line, text, "a value")?;
            current[s.offset + k] = if angle {
                angle_unit.to_radians(v)
            } else if v.abs() <= MAX_TRANSLATION {
                v
            } else {
                return Err(ParseError {
                    line,
                    kind: ParseErrorKind::OutOfRange {
                        what: "the root's position",
                        value: v,
                        range: "±1000000",
                    },
                });
            };
        }
    }
    let Some(last) = frame else {
        return Err(ParseError {
            line: lines.last_line(),
            kind: ParseErrorKind::NoFrames,
        });
    };
    complete(last, &slots, &given)?;
    values.extend_from_slice(&current);
    Ok(Motion {
        frame_rate,
        values,
        channels_per_frame,
        frames,
    })
}

/// The `:keyword` lines before the first frame: the frame rate and the angle unit (the
/// skeleton's unless `:DEGREES` or `:RADIANS` says otherwise).
fn header(lines: &mut Lines, skeleton_unit: AngleUnit) -> Result<(f64, AngleUnit), ParseError> {
    let mut rate = None;
    let mut unit = None;
    let mut fully_specified = false;
    while let Some((line, tokens)) = lines.peek()? {
        let (line, keyword) = (*line, tokens[0].to_ascii_uppercase());
        if !keyword.starts_with(':') {
            break;
        }
        let args = tokens.len() - 1;
        let repeated = match (keyword.as_str(), args) {
            (":FULLY-SPECIFIED", 0) => std::mem::replace(&mut fully_specified, true),
            (":DEGREES", 0) => unit.replace(AngleUnit::Degrees).is_some(),
            (":RADIANS", 0) => unit.replace(AngleUnit::Radians).is_some(),
            (":SAMPLES-PER-SECOND", 1) => {
                let hz = number(line, tokens[1], "samples per second")?;
                if !SAMPLE_RATES.contains(&hz) {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::OutOfRange {
                            what: ":SAMPLES-PER-SECOND",
                            value: hz,
                            range: "1 to 10000",
                        },
                    });
                }
                rate.replace(hz).is_some()
            }
            _ => {
                return Err(unexpected(
                    line,
                    ":FULLY-SPECIFIED, :DEGREES, :RADIANS or :SAMPLES-PER-SECOND N",
                    &tokens.join(" "),
                ))
            }
        };
        if repeated {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::Repeated(format!("{keyword} (or its opposite)")),
            });
        }
        lines.next()?;
    }
    Ok((
        rate.unwrap_or(CMU_FRAME_RATE),
        unit.unwrap_or(skeleton_unit),
    ))
}

/// Checks the frame that began at `line` gave every bone that has values.
fn complete(
    (line, number): (usize, u64),
    slots: &[Slot],
    given: &[bool],
) -> Result<(), ParseError> {
    match slots.iter().zip(given).find(|(s, &g)| s.count > 0 && !g) {
        Some((missing, _)) => Err(ParseError {
            line,
            kind: ParseErrorKind::IncompleteFrame {
                frame: number,
                bone: shown(missing.name),
            },
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests;
