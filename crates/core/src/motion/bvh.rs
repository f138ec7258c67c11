//! A hand-written reader for Biovision Hierarchy (BVH) motion capture: the skeleton
//! (HIERARCHY) and the per-frame channel values (MOTION), nothing interpreted yet.
//!
//! The text is split on whitespace, so CRLF, LF and tabs are all the same to it, but
//! every token keeps its 1-based line number: a bad file is reported at the line where
//! it goes wrong, which is what someone fixing it needs. Values are not range-checked
//! (real captures have the odd glitch spike, and dropping a clip for one is worse than
//! keeping it); they only have to be finite numbers.

use glam::DVec3;
use thiserror::Error;

/// A BVH file that cannot be read, and the 1-based line where it goes wrong.
use super::line_error::{number, shown, TokenError};

pub(super) type ParseError = super::line_error::LineError<ParseErrorKind>;

#[derive(Debug, Clone, PartialEq, Error)]
pub(super) enum ParseErrorKind {
    #[error(transparent)]
    Token(#[from] TokenError),
    #[error("unknown channel {0} (channels are X/Y/Z position and X/Y/Z rotation)")]
    UnknownChannel(String),
    #[error("channel {0} is given twice for one joint")]
    RepeatedChannel(String),
    #[error("CHANNELS {0}: a joint has at most six channels")]
    TooManyChannels(usize),
    #[error("Frame Time {0} is outside 0.0001 to 1 s (capture at 1 Hz to 10 kHz)")]
    BadFrameTime(f64),
    #[error("expected {expected} channel values, found {found}")]
    ChannelCount { expected: usize, found: usize },
    #[error("Frames: says {declared} but {found} frame lines follow")]
    FrameCount { declared: usize, found: usize },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub(super) fn unit(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
        }
    }
}

/// One animated degree of freedom: a translation in file units or a rotation in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Channel {
    Position(Axis),
    Rotation(Axis),
}

impl Channel {
    fn parse(name: &str) -> Option<Channel> {
        // Exporters disagree on capitalisation (`Xrotation`, `XROTATION`); the meaning
        // is never in doubt, so accept any.
        const NAMES: [(&str, Channel); 6] = [
            ("Xposition", Channel::Position(Axis::X)),
            ("Yposition", Channel::Position(Axis::Y)),
            ("Zposition", Channel::Position(Axis::Z)),
            ("Xrotation", Channel::Rotation(Axis::X)),
            ("Yrotation", Channel::Rotation(Axis::Y)),
            ("Zrotation", Channel::Rotation(Axis::Z)),
        ];
        NAMES
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|&(_, c)| c)
    }
}

/// A joint of the hierarchy. End Sites are not joints: they only mark where the last
/// bone ends, and nothing downstream uses that.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Joint {
    pub name: String,
    /// Always an earlier joint: joints are listed parent before child.
    pub parent: Option<usize>,
    /// Position in the parent's frame, in file units.
    pub offset: DVec3,
    /// In file order, which is also the order the rotations compose in.
    pub channels: Vec<Channel>,
}

/// A parsed BVH file: the skeleton and the raw channel values of every frame.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Bvh {
    pub joints: Vec<Joint>,
    /// Seconds between frames, as written in the file.
    pub frame_time: f64,
    /// Channel values, frame-major, joints in order, each joint's channels in order.
    values: Vec<f64>,
    channels_per_frame: usize,
}

impl Bvh {
    pub(super) fn frame_count(&self) -> usize {
        self.values
            .len()
            .checked_div(self.channels_per_frame)
            .unwrap_or(0)
    }

    pub(super) fn frame(&self, f: usize) -> &[f64] {
        let n = self.channels_per_frame;
        &self.values[f * n..(f + 1) * n]
    }
}

/// The shortest and longest frame times a capture may have, seconds.
const MIN_FRAME_TIME_S: f64 = 1e-4;
const MAX_FRAME_TIME_S: f64 = 1.0;

/// Reads a whole BVH file.
pub(super) fn parse(text: &str) -> Result<Bvh, ParseError> {
    let lines: Vec<(usize, Vec<&str>)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split_whitespace().collect::<Vec<_>>()))
        .filter(|(_, tokens)| !tokens.is_empty())
        .collect();
    let mut cursor = Cursor {
        lines: &lines,
        line: 0,
        token: 0,
    };
    let joints = hierarchy(&mut cursor)?;
    let channels_per_frame = joints.iter().map(|j| j.channels.len()).sum();

    cursor.keyword("MOTION")?;
    let frames_line = cursor.keyword("Frames:")?;
    let declared = cursor.count("a frame count")?;
    cursor.keyword("Frame")?;
    cursor.keyword("Time:")?;
    let (time_line, frame_time) = cursor.number("Frame Time")?;
    // Capture runs at 1 Hz to 10 kHz. A frame time outside that is a corrupt file, and
    // a huge one would make resampling allocate a frame for every 1/30 s of it: the
    // fuzzer's `Frame Time: 40617321` asked for 3.6 billion.
    if !(MIN_FRAME_TIME_S..=MAX_FRAME_TIME_S).contains(&frame_time) {
        return Err(ParseError {
            line: time_line,
            kind: ParseErrorKind::BadFrameTime(frame_time),
        });
    }
    // The frame lines are the lines after the frame time, so it must end its line.
    if let Some((line, found)) = cursor.peek() {
        if line == time_line {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::Token(TokenError::Unexpected {
                    expected: "the end of the line after Frame Time",
                    found: found.to_string(),
                }),
            });
        }
    }

    let frame_lines = cursor.rest();
    let mut values = Vec::with_capacity(frame_lines.len() * channels_per_frame);
    for (line, tokens) in frame_lines {
        if tokens.len() != channels_per_frame {
            return Err(ParseError {
                line: *line,
                kind: ParseErrorKind::ChannelCount {
                    expected: channels_per_frame,
                    found: tokens.len(),
                },
            });
        }
        for text in tokens {
            values.push(number(*line, text, "channel value")?);
        }
    }
    if frame_lines.len() != declared {
        return Err(ParseError {
            line: frames_line,
            kind: ParseErrorKind::FrameCount {
                declared,
                found: frame_lines.len(),
            },
        });
    }
    Ok(Bvh {
        joints,
        frame_time,
        values,
        channels_per_frame,
    })
}

/// Reads HIERARCHY up to the root's closing brace. Iterative, with an explicit stack
/// of open joints, so a deeply nested (or hostile) file cannot overflow the call stack.
fn hierarchy(cursor: &mut Cursor) -> Result<Vec<Joint>, ParseError> {
    cursor.keyword("HIERARCHY")?;
    cursor.keyword("ROOT")?;
    let mut joints = vec![joint_body(cursor, None)?];
    let mut open = vec![0];
    while let Some(&parent) = open.last() {
        let (line, token) = cursor.next("JOINT, End Site or }")?;
        match token {
            "JOINT" => {
                joints.push(joint_body(cursor, Some(parent))?);
                open.push(joints.len() - 1);
            }
            "End" => {
                cursor.keyword("Site")?;
                cursor.keyword("{")?;
                cursor.keyword("OFFSET")?;
                cursor.vector("End Site OFFSET")?;
                cursor.keyword("}")?;
            }
            "}" => {
                open.pop();
            }
            other => {
                return Err(ParseError {
                    line,
                    kind: ParseErrorKind::Token(TokenError::Unexpected {
                        expected: "JOINT, End Site or }",
                        found: shown(other),
                    }),
                })
            }
        }
    }
    Ok(joints)
}

/// Reads a joint's name, `{`, OFFSET and CHANNELS; its children follow.
fn joint_body(cursor: &mut Cursor, parent: Option<usize>) -> Result<Joint, ParseError> {
    let (_, name) = cursor.next("a joint name")?;
    cursor.keyword("{")?;
    cursor.keyword("OFFSET")?;
    let offset = cursor.vector("OFFSET")?;
    let channels_line = cursor.keyword("CHANNELS")?;
    let count = cursor.count("a channel count")?;
    if count > 6 {
        return Err(ParseError {
            line: channels_line,
            kind: ParseErrorKind::TooManyChannels(count),
        });
    }
    let mut channels = Vec::with_capacity(count);
    for _ in 0..count {
        let (line, text) = cursor.next("a channel name")?;
        let channel = Channel::parse(text).ok_or_else(|| ParseError {
            line,
            kind: ParseErrorKind::UnknownChannel(text.to_string()),
        })?;
        if channels.contains(&channel) {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::RepeatedChannel(text.to_string()),
            });
        }
        channels.push(channel);
    }
    Ok(Joint {
        name: name.to_string(),
        parent,
        offset,
        channels,
    })
}

/// Walks the tokens line by line, so every token comes with its line number.
struct Cursor<'a> {
    lines: &'a [(usize, Vec<&'a str>)],
    /// Index into `lines` and into that line's tokens.
    line: usize,
    token: usize,
}

impl<'a> Cursor<'a> {
    fn peek(&self) -> Option<(usize, &'a str)> {
        let (number, tokens) = self.lines.get(self.line)?;
        Some((*number, tokens[self.token]))
    }

    fn next(&mut self, expected: &'static str) -> Result<(usize, &'a str), ParseError> {
        let found = self.peek().ok_or_else(|| ParseError {
            line: self.lines.last().map_or(1, |(n, _)| *n),
            kind: ParseErrorKind::Token(TokenError::UnexpectedEnd { expected }),
        })?;
        self.token += 1;
        if self.token == self.lines[self.line].1.len() {
            self.line += 1;
            self.token = 0;
        }
        Ok(found)
    }

    /// Consumes `word` or fails; returns its line.
    fn keyword(&mut self, word: &'static str) -> Result<usize, ParseError> {
        let (line, found) = self.next(word)?;
        if found == word {
            Ok(line)
        } else {
            Err(ParseError {
                line,
                kind: ParseErrorKind::Token(TokenError::Unexpected {
                    expected: word,
                    found: found.to_string(),
                }),
            })
        }
    }

    fn number(&mut self, what: &'static str) -> Result<(usize, f64), ParseError> {
        let (line, text) = self.next(what)?;
        Ok((line, number(line, text, what)?))
    }

    fn vector(&mut self, what: &'static str) -> Result<DVec3, ParseError> {
        let (_, x) = self.number(what)?;
        let (_, y) = self.number(what)?;
        let (_, z) = self.number(what)?;
        Ok(DVec3::new(x, y, z))
    }

    fn count(&mut self, what: &'static str) -> Result<usize, ParseError> {
        let (line, text) = self.next(what)?;
        text.parse().map_err(|_| ParseError {
            line,
            kind: ParseErrorKind::Token(TokenError::Unexpected {
                expected: what,
                found: text.to_string(),
            }),
        })
    }

    /// The lines not yet read. Only called at a line boundary.
    fn rest(&self) -> &'a [(usize, Vec<&'a str>)] {
        debug_assert_eq!(self.token, 0);
        &self.lines[self.line..]
    }
}

#[cfg(test)]
pub(super) mod tests;
