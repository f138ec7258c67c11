//! Frames carry a millimetre: every floating-point number in a frame is rounded to three
//! decimals as it is written. `99.67935425784906` costs 17 bytes to send and `99.679`
//! 6, and a frame goes to every spectator 30 times a second. A millimetre, a milliradian
//! (0.06°) and a millisecond are what a viewer can see.
//!
//! The rounding is done by the serializer (a `serde_json` [`Formatter`]), not by the
//! types: the world and its views keep full precision, and the same views go to bots
//! unrounded in their perceptions. Replays re-simulate and write frames the same way,
//! so they still verify bit for bit.

use serde::Serialize;
use serde_json::ser::{CompactFormatter, Formatter};
use std::io;

/// Decimal places kept in frames, as a scale: 10³.
const FRAME_DECIMALS: f64 = 1000.0;

/// `x` to [`FRAME_DECIMALS`]. A number too large to scale stays as it is (it has no
/// fraction to round).
pub(super) fn quantised(x: f64) -> f64 {
    let q = (x * FRAME_DECIMALS).round() / FRAME_DECIMALS;
    if q.is_finite() {
        q
    } else {
        x
    }
}

/// Below this many thousandths (10¹², a billion metres) a rounded number is written as
/// an integer count of thousandths. The doubles there are finer than a thousandth
/// (their spacing is at most 2⁻¹⁰), so the shortest decimal that reads back as the
/// rounded double, which is what serde_json writes, is exactly the count of thousandths
/// with its trailing zeros dropped: the same bytes, without the general shortest-digits
/// search (which was a sixth of a fly-ball run's encoding).
const EXACT_THOUSANDTHS: f64 = 1e15;

/// Compact JSON with every float rounded by [`quantised`], written as serde_json writes
/// any float (so `1.0` stays `1.0` and `-0.0` stays `-0.0`, as protocol 2 wrote them).
struct Quantising;

impl Formatter for Quantising {
    fn write_f64<W: ?Sized + io::Write>(&mut self, writer: &mut W, value: f64) -> io::Result<()> {
        let thousandths = (value * FRAME_DECIMALS).round();
        if thousandths.abs() >= EXACT_THOUSANDTHS || !thousandths.is_finite() {
            return CompactFormatter.write_f64(writer, quantised(value));
        }
        // Exact: a whole number below 2⁵³.
        let n = thousandths.abs() as u64;
        if thousandths.is_sign_negative() {
            writer.write_all(b"-")?;
        }
        let mut digits = itoa::Buffer::new();
        writer.write_all(digits.format(n / 1000).as_bytes())?;
        let fraction = n % 1000;
        let text: &[u8] = match fraction {
            0 => b".0",
            _ => {
                let (mut kept, mut len) = (fraction, 3);
                while kept % 10 == 0 {
                    kept /= 10;
                    len -= 1;
                }
                writer.write_all(b".")?;
                let text = digits.format(kept).as_bytes();
                // The fraction's leading zeros: five thousandths are ".005".
                for _ in text.len()..len {
                    writer.write_all(b"0")?;
                }
                text
            }
        };
        writer.write_all(text)
    }

    fn write_f32<W: ?Sized + io::Write>(&mut self, writer: &mut W, value: f32) -> io::Result<()> {
        CompactFormatter.write_f64(writer, quantised(f64::from(value)))
    }
}

/// Appends `message` to `out` as compact JSON with its floats rounded to a millimetre.
pub(super) fn write(out: &mut Vec<u8>, message: &impl Serialize) {
    let mut serializer = serde_json::Serializer::with_formatter(out, Quantising);
    message
        .serialize(&mut serializer)
        .expect("protocol messages serialise");
}

#[cfg(test)]
mod tests {
    use super::{quantised, write};
    use proptest::prelude::*;
    use serde_json::json;

    /// What serde_json itself writes for `x` rounded: the oracle for the fast path.
    fn by_serde_json(x: f64) -> String {
        serde_json::to_string(&quantised(x)).unwrap()
    }

    fn by_frames(x: f64) -> String {
        let mut out = Vec::new();
        write(&mut out, &x);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn thousandths_are_written_as_serde_json_writes_their_doubles() {
        for x in [
            0.0,
            -0.0,
            0.0004,
            -0.0004,
            0.0005,
            -0.0005,
            0.001,
            -0.005,
            0.01,
            0.1,
            0.5,
            1.0,
            -1.0,
            1.5,
            2.25,
            9.999,
            9.9995,
            99.67935425784906,
            1000.0,
            12345.678,
            1e9 + 0.001,
            999_999_999_999.999,
            1e12 - 0.0005,
            1e12,
            1e12 + 0.5,
            -1e12,
            1e14,
            1e15,
            1e300,
            f64::MAX,
            f64::MIN_POSITIVE,
            1e-300,
            -1e-7,
            36.36666666666667,
        ] {
            assert_eq!(by_frames(x), by_serde_json(x), "{x:e}");
        }
        assert_eq!(by_frames(f64::NAN), "null");
        assert_eq!(by_frames(f64::INFINITY), "null");
    }

    proptest! {
        #[test]
        fn any_number_is_written_as_serde_json_writes_it_rounded(
            mantissa in -1.0f64..1.0,
            exponent in -6i32..16,
        ) {
            let x = mantissa * 10f64.powi(exponent);
            prop_assert_eq!(by_frames(x), by_serde_json(x));
        }

        #[test]
        fn any_bit_pattern_is_written_as_serde_json_writes_it_rounded(bits in any::<u64>()) {
            let x = f64::from_bits(bits);
            prop_assert_eq!(by_frames(x), by_serde_json(x));
        }
    }

    #[test]
    fn floats_keep_a_millimetre_and_integers_stay_whole() {
        let mut out = Vec::new();
        let v = json!({"n": [1.0005, {"h": 1.23456789}], "position": [99.67935425784906, -0.00049, 2.0], "tick": 12, "huge": 1e306, "t": 0.1f32});
        write(&mut out, &v);
        assert_eq!(
            String::from_utf8(out).unwrap(),
            r#"{"huge":1e+306,"n":[1.001,{"h":1.235}],"position":[99.679,-0.0,2.0],"t":0.1,"tick":12}"#
        );
    }
}
