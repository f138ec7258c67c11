//! A hand-written reader for Acclaim skeleton files (ASF), CMU's native skeleton format:
//! the bones, their lengths, directions and local axes, the degrees of freedom each one
//! has, and how they hang together. The motion that drives it is an AMC file (`amc`),
//! and `acclaim` turns the two into joint positions.
//!
//! Strict, like `bvh`: every error names its 1-based line, and anything this reader
//! cannot interpret with certainty is refused rather than guessed. That covers three
//! things CMU's files never use and other tools read differently: axis orders other than
//! `XYZ`, rotation degrees of freedom listed out of x, y, z order, and a root placed
//! away from the origin (`position`, `orientation`). Translation and length degrees of
//! freedom are refused too.
//!
//! Bounded on hostile input: lines are at most [`MAX_LINE_BYTES`], a skeleton has at most
//! [`MAX_BONES`] bones, lengths and the unit are range-checked so no position can
//! overflow, and nothing recurses. The text is read once, line by line, so time and
//! memory grow with the file and nothing else. The AMC reader shares the line handling
//! and the error type.

use super::bvh::Axis;
use glam::{DQuat, DVec3};
use std::collections::BTreeMap;
use thiserror::Error;

/// The longest line either reader accepts, bytes. CMU's longest are under 100; the cap
/// keeps a hostile line from being echoed or split at length.
pub(super) const MAX_LINE_BYTES: usize = 4096;
/// The most bones a skeleton may have: CMU's have 30, detailed hands take a few dozen more.
pub(super) const MAX_BONES: usize = 256;
/// The longest bone, in file units: CMU's longest is 7.4 (42 cm).
const MAX_BONE_LENGTH: f64 = 1e4;
/// The range of `:units length`: CMU's is 0.45.
const LENGTH_MULTIPLIER: std::ops::RangeInclusive<f64> = 1e-3..=1e3;
/// How far a `direction` may be from unit length: CMU's are within 1e-6.
const UNIT_TOLERANCE: f64 = 1e-3;
/// Metres per inch: CMU's skeletons are measured in inches (see [`Skeleton::metres_per_unit`]).
const METRES_PER_INCH: f64 = 0.0254;

/// An ASF or AMC file that cannot be read, and the 1-based line where it goes wrong.
pub(super) use super::line_error::{number, shown, TokenError};

pub(super) type ParseError = super::line_error::LineError<ParseErrorKind>;

#[derive(Debug, Clone, PartialEq, Error)]
pub(super) enum ParseErrorKind {
    #[error("the line is longer than {MAX_LINE_BYTES} bytes")]
    LineTooLong,
    #[error(transparent)]
    Token(#[from] TokenError),
    #[error("{what} {value} is outside {range}")]
    OutOfRange {
        what: &'static str,
        value: f64,
        range: &'static str,
    },
    #[error("{0} is given twice")]
    Repeated(String),
    #[error("no {0}")]
    Missing(&'static str),
    #[error("{0}")]
    Unsupported(&'static str),
    #[error("more than {MAX_BONES} bones")]
    TooManyBones,
    #[error("bone `{0}` is not in the skeleton")]
    UnknownBone(String),
    #[error("bone `{bone}` has no place in :hierarchy, so nothing says where it starts")]
    Unplaced { bone: String },
    #[error("the direction has length {0:.4}, not 1")]
    NotAUnitVector(f64),
    // What only AMC files can get wrong.
    #[error("no frames")]
    NoFrames,
    #[error("frame number {found} where {expected} was expected (frames are numbered one by one)")]
    FrameNumber { expected: u64, found: String },
    #[error("more than {max} frames (the cap for a skeleton of {joints} joints)")]
    TooManyFrames { max: usize, joints: usize },
    #[error("frame {frame} has no line for `{bone}`")]
    IncompleteFrame { frame: u64, bone: String },
    #[error("`{bone}` takes {}, found {found}", values(*.expected))]
    ValueCount {
        bone: String,
        expected: usize,
        found: usize,
    },
}

fn values(n: usize) -> String {
    match n {
        1 => "1 value".to_string(),
        n => format!("{n} values"),
    }
}

/// The unit of every angle in a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum AngleUnit {
    Degrees,
    Radians,
}

impl AngleUnit {
    pub(super) fn to_radians(self, value: f64) -> f64 {
        match self {
            AngleUnit::Degrees => value.to_radians(),
            AngleUnit::Radians => value,
        }
    }
}

/// One value of the root's line in an AMC frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RootChannel {
    Translation(Axis),
    Rotation(Axis),
}

/// A bone: it starts where its parent ends (the root's position for a bone of the root)
/// and ends `length` along `direction`, both given in the global frame of the zero pose.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Bone {
    pub name: String,
    /// An earlier bone of [`Skeleton::bones`], or `None` for a bone of the root.
    pub parent: Option<usize>,
    /// Unit vector, global, zero pose.
    pub direction: DVec3,
    /// File units.
    pub length: f64,
    /// The bone's local axes in the global frame, C: from the `axis a b c XYZ` line,
    /// C = Rz(c)·Ry(b)·Rx(a), X applied first.
    pub axis: DQuat,
    /// The rotations an AMC frame gives it, in the order its values come: a subset of
    /// x, y, z in that order.
    pub dofs: Vec<Axis>,
}

/// A parsed ASF file.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Skeleton {
    /// Metres per length unit: 0.0254 / `:units length`. Acclaim's `length` is the
    /// factor the skeleton's lengths were multiplied by, and CMU measures in inches, so a
    /// file unit is 1/`length` inches; for CMU's 0.45 that is (1/0.45)·2.54/100 = 0.056444
    /// m, CMU's own conversion.
    pub metres_per_unit: f64,
    /// The unit of the `axis` angles here and, unless the AMC says otherwise, of its values.
    pub angle_unit: AngleUnit,
    /// The values of the root's line in an AMC frame, in order. Rotations come in x, y,
    /// z order and compose as the bones' do.
    pub root: Vec<RootChannel>,
    /// Depth first from the root, children in the order `:hierarchy` lists them: parents
    /// come before children, and CMU's bones come in the order Hahne's BVH lists them.
    pub bones: Vec<Bone>,
}

/// Reads a whole ASF file.
pub(super) fn parse(text: &str) -> Result<Skeleton, ParseError> {
    let mut lines = Lines::new(text);
    let mut seen: Vec<&str> = Vec::new();
    let mut units = None;
    let mut root = None;
    let mut bones = None;
    let mut hierarchy = None;
    while let Some((line, tokens)) = lines.next()? {
        let section = tokens[0];
        if seen.contains(&section) {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::Repeated(section.to_string()),
            });
        }
        match section {
            // One value on the keyword's line; nothing here depends on it.
            ":version" | ":name" => {
                if tokens.len() < 2 {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::Missing("value after the keyword"),
                    });
                }
            }
            ":documentation" => while lines.next_in_section()?.is_some() {},
            ":units" => units = Some(parse_units(&mut lines, line)?),
            ":root" => root = Some(parse_root(&mut lines, line)?),
            ":bonedata" => bones = Some(parse_bonedata(&mut lines)?),
            ":hierarchy" => hierarchy = Some(parse_hierarchy(&mut lines, line)?),
            other => {
                return Err(ParseError {
                    line,
                    kind: ParseErrorKind::Token(TokenError::Unexpected {
                        expected: "a section (:units, :root, :bonedata, :hierarchy, ...)",
                        found: shown(other),
                    }),
                })
            }
        }
        if section != ":documentation" && section != ":version" && section != ":name" {
            // The keyword must be alone on its line; its body follows.
            if tokens.len() > 1 {
                return Err(unexpected(line, "the end of the line", tokens[1]));
            }
        }
        seen.push(section);
    }
    let end = lines.last_line();
    let missing = |what| ParseError {
        line: end,
        kind: ParseErrorKind::Missing(what),
    };
    let (metres_per_unit, angle_unit) = units.ok_or_else(|| missing(":units section"))?;
    let root = root.ok_or_else(|| missing(":root section"))?;
    let raw = bones.ok_or_else(|| missing(":bonedata section"))?;
    let (hierarchy_line, links) = hierarchy.ok_or_else(|| missing(":hierarchy section"))?;
    let bones = arrange(raw, &links, hierarchy_line, angle_unit)?;
    Ok(Skeleton {
        metres_per_unit,
        angle_unit,
        root,
        bones,
    })
}

/// `:units`: `mass`, `length` (required) and `angle` (`deg`, the default, or `rad`).
fn parse_units(lines: &mut Lines, line: usize) -> Result<(f64, AngleUnit), ParseError> {
    let mut length = None;
    let mut angle = None;
    let mut mass_seen = false;
    while let Some((line, tokens)) = lines.next_in_section()? {
        let [key, value] = tokens[..] else {
            return Err(unexpected(line, "a unit and its value", tokens[0]));
        };
        let repeated = match key {
            "mass" => {
                number(line, value, "mass")?;
                std::mem::replace(&mut mass_seen, true)
            }
            "length" => {
                let v = number(line, value, "length")?;
                if !LENGTH_MULTIPLIER.contains(&v) {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::OutOfRange {
                            what: ":units length",
                            value: v,
                            range: "0.001 to 1000",
                        },
                    });
                }
                length.replace(v).is_some()
            }
            "angle" => {
                let unit = match value.to_ascii_lowercase().as_str() {
                    "deg" | "degrees" => AngleUnit::Degrees,
                    "rad" | "radians" => AngleUnit::Radians,
                    _ => return Err(unexpected(line, "deg or rad", value)),
                };
                angle.replace(unit).is_some()
            }
            other => return Err(unexpected(line, "mass, length or angle", other)),
        };
        if repeated {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::Repeated(format!(":units {key}")),
            });
        }
    }
    let length = length.ok_or(ParseError {
        line,
        kind: ParseErrorKind::Missing(":units length (the scale of every length)"),
    })?;
    Ok((
        METRES_PER_INCH / length,
        angle.unwrap_or(AngleUnit::Degrees),
    ))
}

/// `:root`: the AMC root line's `order`, the `axis` order (`XYZ`), and a `position` and
/// `orientation` that must be zero.
fn parse_root(lines: &mut Lines, section_line: usize) -> Result<Vec<RootChannel>, ParseError> {
    let mut order = None;
    let mut axis_seen = false;
    while let Some((line, tokens)) = lines.next_in_section()? {
        let key = tokens[0];
        match key {
            "order" => {
                let mut channels = Vec::new();
                for &name in &tokens[1..] {
                    let channel = root_channel(name)
                        .ok_or_else(|| unexpected(line, "TX, TY, TZ, RX, RY or RZ", name))?;
                    if channels.contains(&channel) {
                        return Err(ParseError {
                            line,
                            kind: ParseErrorKind::Repeated(format!("root channel {name}")),
                        });
                    }
                    channels.push(channel);
                }
                let rotations: Vec<Axis> = channels
                    .iter()
                    .filter_map(|c| match c {
                        RootChannel::Rotation(axis) => Some(*axis),
                        RootChannel::Translation(_) => None,
                    })
                    .collect();
                check_xyz_order(line, &rotations)?;
                if order.replace(channels).is_some() {
                    return Err(repeated(line, ":root order"));
                }
            }
            "axis" => {
                let [_, order] = tokens[..] else {
                    return Err(unexpected(line, "one axis order (XYZ)", tokens[0]));
                };
                check_axis_order(line, order)?;
                if std::mem::replace(&mut axis_seen, true) {
                    return Err(repeated(line, ":root axis"));
                }
            }
            "position" | "orientation" => {
                let v = vector(line, &tokens[1..], "root position or orientation")?;
                if v != DVec3::ZERO {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::Unsupported(
                            "a root position or orientation other than 0 0 0: CMU's are \
                             zero, and readers disagree on how to apply them",
                        ),
                    });
                }
            }
            other => {
                return Err(unexpected(
                    line,
                    "order, axis, position or orientation",
                    other,
                ))
            }
        }
    }
    order.ok_or(ParseError {
        line: section_line,
        kind: ParseErrorKind::Missing(":root order (the channels of the root's line)"),
    })
}

fn root_channel(name: &str) -> Option<RootChannel> {
    let axis = match name.get(1..)?.to_ascii_uppercase().as_str() {
        "X" => Axis::X,
        "Y" => Axis::Y,
        "Z" => Axis::Z,
        _ => return None,
    };
    match name.get(..1)?.to_ascii_uppercase().as_str() {
        "T" => Some(RootChannel::Translation(axis)),
        "R" => Some(RootChannel::Rotation(axis)),
        _ => None,
    }
}

/// The one axis order read: `XYZ`, X applied first. Every CMU file uses it; for other
/// orders readers disagree on whether the three angles follow the letters.
fn check_axis_order(line: usize, order: &str) -> Result<(), ParseError> {
    if order.eq_ignore_ascii_case("XYZ") {
        Ok(())
    } else {
        Err(ParseError {
            line,
            kind: ParseErrorKind::Unsupported(
                "an axis order other than XYZ (CMU's only order; readers disagree on others)",
            ),
        })
    }
}

/// Rotations listed in x, y, z order (any subset): the only order CMU's files use, and
/// the one every reader composes the same way (x first).
fn check_xyz_order(line: usize, axes: &[Axis]) -> Result<(), ParseError> {
    let rank = |a: &Axis| match a {
        Axis::X => 0,
        Axis::Y => 1,
        Axis::Z => 2,
    };
    if axes.windows(2).all(|w| rank(&w[0]) < rank(&w[1])) {
        Ok(())
    } else {
        Err(ParseError {
            line,
            kind: ParseErrorKind::Unsupported(
                "rotations listed out of x, y, z order (CMU's files never are; readers \
                 disagree on what order they compose in)",
            ),
        })
    }
}

/// A bone as `:bonedata` gives it, before `:hierarchy` places it.
struct RawBone {
    line: usize,
    name: String,
    direction: DVec3,
    length: f64,
    /// Angles in the file's unit, X Y Z.
    axis: DVec3,
    dofs: Vec<Axis>,
}

/// `:bonedata`: `begin` ... `end` blocks, one per bone.
fn parse_bonedata(lines: &mut Lines) -> Result<Vec<RawBone>, ParseError> {
    let mut bones: Vec<RawBone> = Vec::new();
    while let Some((line, tokens)) = lines.next_in_section()? {
        if tokens != ["begin"] {
            return Err(unexpected(line, "begin", tokens[0]));
        }
        if bones.len() == MAX_BONES {
            return Err(ParseError {
                line,
                kind: ParseErrorKind::TooManyBones,
            });
        }
        let bone = parse_bone(lines, line)?;
        if bones.iter().any(|b| b.name == bone.name) {
            return Err(repeated(
                bone.line,
                &format!("bone `{}`", shown(&bone.name)),
            ));
        }
        bones.push(bone);
    }
    Ok(bones)
}

/// One bone's block, from the line after `begin` to `end`.
fn parse_bone(lines: &mut Lines, begin: usize) -> Result<RawBone, ParseError> {
    let mut name = None;
    let mut direction = None;
    let mut length = None;
    let mut axis = None;
    let mut dofs: Option<Vec<Axis>> = None;
    let mut limits = None;
    let mut seen: Vec<&str> = Vec::new();
    loop {
        let Some((line, tokens)) = lines.next_in_section()? else {
            return Err(ParseError {
                line: lines.last_line(),
                kind: ParseErrorKind::Token(TokenError::UnexpectedEnd {
                    expected: "the end of a bone",
                }),
            });
        };
        let key = tokens[0];
        if key == "end" && tokens.len() == 1 {
            break;
        }
        if seen.contains(&key) {
            return Err(repeated(line, key));
        }
        seen.push(key);
        let args = &tokens[1..];
        match key {
            "id" => match args {
                [id] if id.parse::<u32>().is_ok() => {}
                _ => return Err(unexpected(line, "a bone id", args.first().unwrap_or(&""))),
            },
            "name" => {
                let [text] = args else {
                    return Err(unexpected(
                        line,
                        "one bone name",
                        args.first().unwrap_or(&""),
                    ));
                };
                // A name of digits alone would read as a frame number in an AMC file.
                if text.eq_ignore_ascii_case("root") || text.bytes().all(|b| b.is_ascii_digit()) {
                    return Err(unexpected(
                        line,
                        "a bone name (not `root` or a number)",
                        text,
                    ));
                }
                name = Some((line, text.to_string()));
            }
            "direction" => {
                let v = vector(line, args, "direction")?;
                if (v.length() - 1.0).abs() > UNIT_TOLERANCE {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::NotAUnitVector(v.length()),
                    });
                }
                direction = Some(v);
            }
            "length" => {
                let [text] = args else {
                    return Err(unexpected(line, "one length", args.first().unwrap_or(&"")));
                };
                let v = number(line, text, "length")?;
                if !(0.0..=MAX_BONE_LENGTH).contains(&v) {
                    return Err(ParseError {
                        line,
                        kind: ParseErrorKind::OutOfRange {
                            what: "length",
                            value: v,
                            range: "0 to 10000",
                        },
                    });
                }
                length = Some(v);
            }
            "axis" => {
                let [x, y, z, order] = args else {
                    return Err(unexpected(
                        line,
                        "three angles and an order (XYZ)",
                        args.first().unwrap_or(&""),
                    ));
                };
                check_axis_order(line, order)?;
                axis = Some(DVec3::new(
                    number(line, x, "axis")?,
                    number(line, y, "axis")?,
                    number(line, z, "axis")?,
                ));
            }
            "dof" => {
                let mut list = Vec::new();
                for &text in args {
                    let axis = match text.to_ascii_lowercase().as_str() {
                        "rx" => Axis::X,
                        "ry" => Axis::Y,
                        "rz" => Axis::Z,
                        "tx" | "ty" | "tz" | "l" => {
                            return Err(ParseError {
                                line,
                                kind: ParseErrorKind::Unsupported(
                                    "translation and length degrees of freedom (CMU's bones only rotate)",
                                ),
                            })
                        }
                        _ => return Err(unexpected(line, "rx, ry or rz", text)),
                    };
                    if list.contains(&axis) {
                        return Err(repeated(line, &format!("dof {text}")));
                    }
                    list.push(axis);
                }
                check_xyz_order(line, &list)?;
                dofs = Some(list);
            }
            "limits" => limits = Some((line, parse_limits(lines, line, args)?)),
            // Mass properties some exporters add; nothing here depends on them.
            "bodymass" | "cofmass" => {
                let [text] = args else {
                    return Err(unexpected(line, "one number", args.first().unwrap_or(&"")));
                };
                number(line, text, "mass")?;
            }
            other => {
                return Err(unexpected(
                    line,
                    "id, name, direction, length, axis, dof, limits or end",
                    other,
                ))
            }
        }
    }
    let missing = |what| ParseError {
        line: begin,
        kind: ParseErrorKind::Missing(what),
    };
    let (line, name) = name.ok_or_else(|| missing("bone name"))?;
    let direction = direction.ok_or_else(|| missing("bone direction"))?;
    let length = length.ok_or_else(|| missing("bone length"))?;
    let axis = axis.ok_or_else(|| missing("bone axis"))?;
    let dofs = dofs.unwrap_or_default();
    match limits {
        Some((line, count)) if count != dofs.len() => Err(ParseError {
            line,
            kind: ParseErrorKind::Token(TokenError::Unexpected {
                expected: "one limit per dof",
                found: format!("{count} limits for {} dofs", dofs.len()),
            }),
        }),
        _ => Ok(RawBone {
            line,
            name,
            direction,
            length,
            axis,
            dofs,
        }),
    }
}

/// `limits (lo hi)`, the first pair on the keyword's line and one more on each line that
/// follows and starts with `(`. Returns how many pairs there are. Nothing here uses the
/// limits (a capture may exceed them), but they must be well formed.
fn parse_limits(lines: &mut Lines, line: usize, args: &[&str]) -> Result<usize, ParseError> {
    let mut pairs = 0;
    let mut text_line = (line, args.join(" "));
    loop {
        let (line, text) = &text_line;
        let spaced = text.replace('(', " ( ").replace(')', " ) ");
        let tokens: Vec<&str> = spaced.split_whitespace().collect();
        let [open, lo, hi, close] = tokens[..] else {
            return Err(unexpected(*line, "one limit, (lo hi)", text));
        };
        if open != "(" || close != ")" {
            return Err(unexpected(*line, "one limit, (lo hi)", text));
        }
        for value in [lo, hi] {
            // A limit may be infinite (`inf` is Acclaim's "no limit"), never NaN.
            if value.parse::<f64>().map_or(true, f64::is_nan) {
                return Err(ParseError {
                    line: *line,
                    kind: ParseErrorKind::Token(TokenError::NotANumber {
                        what: "limit",
                        text: shown(value),
                    }),
                });
            }
        }
        pairs += 1;
        match lines.peek()? {
            Some((next, tokens)) if tokens[0].starts_with('(') => {
                text_line = (*next, tokens.join(" "));
                lines.next()?;
            }
            _ => return Ok(pairs),
        }
    }
}

/// One `parent child` link of `:hierarchy`, with its line.
struct Link {
    line: usize,
    parent: String,
    child: String,
}

/// `:hierarchy`: `begin`, lines of a parent and its children, `end`. Returns the line of
/// `begin` and the links in the order written (lines top to bottom, children left to
/// right), each bone a child at most once.
fn parse_hierarchy(
    lines: &mut Lines,
    section_line: usize,
) -> Result<(usize, Vec<Link>), ParseError> {
    let (begin, tokens) = lines.next_in_section()?.ok_or(ParseError {
        line: section_line,
        kind: ParseErrorKind::Token(TokenError::UnexpectedEnd { expected: "begin" }),
    })?;
    if tokens != ["begin"] {
        return Err(unexpected(begin, "begin", tokens[0]));
    }
    let mut links: Vec<Link> = Vec::new();
    loop {
        let Some((line, tokens)) = lines.next_in_section()? else {
            return Err(ParseError {
                line: lines.last_line(),
                kind: ParseErrorKind::Token(TokenError::UnexpectedEnd {
                    expected: "the end of :hierarchy",
                }),
            });
        };
        if tokens == ["end"] {
            return Ok((begin, links));
        }
        let (parent, children) = (tokens[0], &tokens[1..]);
        if children.is_empty() {
            return Err(unexpected(line, "a parent and its children", parent));
        }
        for &child in children {
            if links.iter().any(|l| l.child == child) {
                return Err(repeated(line, &format!("the parent of `{}`", shown(child))));
            }
            // Each bone is a child once, so a skeleton within the cap has no more links
            // than this; the check also keeps the search above linear in the cap.
            if links.len() == MAX_BONES {
                return Err(ParseError {
                    line,
                    kind: ParseErrorKind::TooManyBones,
                });
            }
            links.push(Link {
                line,
                parent: parent.to_string(),
                child: child.to_string(),
            });
        }
    }
}

/// Orders the bones depth first from the root as `:hierarchy` places them, and checks
/// every bone has exactly one place: its parent is the root or a bone, and following
/// parents from it reaches the root (a bone in a cycle never does).
fn arrange(
    raw: Vec<RawBone>,
    links: &[Link],
    hierarchy_line: usize,
    angle_unit: AngleUnit,
) -> Result<Vec<Bone>, ParseError> {
    let index: BTreeMap<&str, usize> = raw
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.as_str(), i))
        .collect();
    // Children of the root (slot 0) and of each bone (slot i + 1), in the order written.
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); raw.len() + 1];
    for link in links {
        let find = |name: &str| {
            index.get(name).copied().ok_or_else(|| ParseError {
                line: link.line,
                kind: ParseErrorKind::UnknownBone(shown(name)),
            })
        };
        let child = find(&link.child)?;
        let parent = if link.parent == "root" {
            0
        } else {
            find(&link.parent)? + 1
        };
        children[parent].push(child);
    }

    let mut bones: Vec<Bone> = Vec::with_capacity(raw.len());
    let mut placed = vec![false; raw.len()];
    // Depth first with an explicit stack of (bone, its parent's index in `bones`), so a
    // deep chain cannot overflow the call stack.
    let mut stack: Vec<(usize, Option<usize>)> =
        children[0].iter().rev().map(|&c| (c, None)).collect();
    while let Some((i, parent)) = stack.pop() {
        let b = &raw[i];
        let [x, y, z] = b.axis.to_array().map(|a| angle_unit.to_radians(a));
        placed[i] = true;
        bones.push(Bone {
            name: b.name.clone(),
            parent,
            direction: b.direction,
            length: b.length,
            axis: DQuat::from_rotation_z(z) * DQuat::from_rotation_y(y) * DQuat::from_rotation_x(x),
            dofs: b.dofs.clone(),
        });
        let me = Some(bones.len() - 1);
        stack.extend(children[i + 1].iter().rev().map(|&c| (c, me)));
    }
    match raw.iter().zip(&placed).find(|(_, &placed)| !placed) {
        Some((lost, _)) => Err(ParseError {
            line: links
                .iter()
                .find(|l| l.child == lost.name)
                .map_or(hierarchy_line, |l| l.line),
            kind: ParseErrorKind::Unplaced {
                bone: shown(&lost.name),
            },
        }),
        None => Ok(bones),
    }
}

fn repeated(line: usize, what: &str) -> ParseError {
    ParseError {
        line,
        kind: ParseErrorKind::Repeated(what.to_string()),
    }
}

pub(super) fn unexpected(line: usize, expected: &'static str, found: &str) -> ParseError {
    ParseError {
        line,
        kind: ParseErrorKind::Token(TokenError::Unexpected {
            expected,
            found: shown(found),
        }),
    }
}

/// Three finite numbers, the rest of a line.
fn vector(line: usize, args: &[&str], what: &'static str) -> Result<DVec3, ParseError> {
    let [x, y, z] = args else {
        return Err(unexpected(
            line,
            "three numbers",
            args.first().unwrap_or(&""),
        ));
    };
    Ok(DVec3::new(
        number(line, x, what)?,
        number(line, y, what)?,
        number(line, z, what)?,
    ))
}

/// The lines of a file that carry something: blank lines and comments (`#` first) are
/// skipped, each line comes split on whitespace with its 1-based number, and a line
/// longer than [`MAX_LINE_BYTES`] is an error.
pub(super) struct Lines<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    peeked: Option<(usize, Vec<&'a str>)>,
    last: usize,
}

impl<'a> Lines<'a> {
    pub(super) fn new(text: &'a str) -> Lines<'a> {
        Lines {
            lines: text.lines().enumerate(),
            peeked: None,
            last: 1,
        }
    }

    pub(super) fn next(&mut self) -> Result<Option<(usize, Vec<&'a str>)>, ParseError> {
        if let Some(line) = self.peeked.take() {
            return Ok(Some(line));
        }
        for (i, text) in self.lines.by_ref() {
            self.last = i + 1;
            if text.len() > MAX_LINE_BYTES {
                return Err(ParseError {
                    line: i + 1,
                    kind: ParseErrorKind::LineTooLong,
                });
            }
            let tokens: Vec<&str> = text.split_whitespace().collect();
            if tokens.first().is_some_and(|t| !t.starts_with('#')) {
                return Ok(Some((i + 1, tokens)));
            }
        }
        Ok(None)
    }

    pub(super) fn peek(&mut self) -> Result<Option<&(usize, Vec<&'a str>)>, ParseError> {
        if self.peeked.is_none() {
            self.peeked = self.next()?;
        }
        Ok(self.peeked.as_ref())
    }

    /// The next line unless it starts a new section (a `:keyword`).
    fn next_in_section(&mut self) -> Result<Option<(usize, Vec<&'a str>)>, ParseError> {
        match self.peek()? {
            Some((_, tokens)) if !tokens[0].starts_with(':') => self.next(),
            _ => Ok(None),
        }
    }

    /// The number of the last line read: where a file that ends too soon ends.
    pub(super) fn last_line(&self) -> usize {
        self.last
    }
}

#[cfg(test)]
pub(super) mod tests;
