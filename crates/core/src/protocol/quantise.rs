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

/// Compact JSON with every float rounded by [`quantised`], written as serde_json writes
/// any float (so `1.0` stays `1.0` and `-0.0` stays `-0.0`, as protocol 2 wrote them).
struct Quantising;

impl Formatter for Quantising {
    fn write_f64<W: ?Sized + io::Write>(&mut self, writer: &mut W, value: f64) -> io::Result<()> {
        CompactFormatter.write_f64(writer, quantised(value))
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
    use super::write;
    use serde_json::json;

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
