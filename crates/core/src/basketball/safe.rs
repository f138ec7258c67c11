//! The safe squares of a decision as they go on the wire: a bitmap over the court's
//! squares, cut to the rows and columns that hold any.
//!
//! A decision can qualify hundreds of squares, and listed one object each they made
//! decision frames 18 KB at the 99th percentile, sent 30 times a second to every
//! spectator. The spectator only needs to outline them, and the court's squares are
//! known from the `hello` (`field.court`), so a bit per square says it all: at most
//! 840 bits (140 base64 characters) on the default court, typically half that.

use super::court::Court;
use super::decision::Candidate;
use base64::engine::general_purpose::STANDARD;
use base64::Engine;
use glam::DVec2;
use serde::Serialize;

/// `bounds` is `[first row, first column, rows, columns]` of the court's squares (row i
/// along z from −width/2, column j along x from the baseline, as
/// [`Court::square_centre`] counts them); bit `r · columns + c` of `bits` (standard
/// base64, least significant bit of each byte first) is set when square (first row + r,
/// first column + c) is safe.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SafeSquares {
    /// The bitmap, standard base64.
    pub(crate) bits: String,
    /// `[first row, first column, rows, columns]` of the box the bitmap covers.
    #[serde(rename = "box")]
    pub(crate) bounds: [usize; 4],
}

impl SafeSquares {
    /// The squares of `candidates` (their centres are squares of `court`); `None` if
    /// there are none.
    pub fn of(court: &Court, candidates: &[Candidate]) -> Option<SafeSquares> {
        let (nx, _) = court.squares_xz();
        let squares: Vec<(usize, usize)> = candidates
            .iter()
            .filter_map(|c| court.square_of(DVec2::from_array(c.cell)))
            .map(|s| (s / nx, s % nx))
            .collect();
        let (i0, j0, i1, j1) = squares
            .iter()
            .map(|&(i, j)| (i, j, i, j))
            .reduce(|a, b| (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3)))?;
        let (rows, columns) = (i1 - i0 + 1, j1 - j0 + 1);
        let mut bytes = vec![0u8; (rows * columns).div_ceil(8)];
        for (i, j) in squares {
            let bit = (i - i0) * columns + (j - j0);
            bytes[bit / 8] |= 1 << (bit % 8);
        }
        Some(SafeSquares {
            bounds: [i0, j0, rows, columns],
            bits: STANDARD.encode(bytes),
        })
    }

    /// The square indices (as [`Court::square_of`] numbers them) the bitmap holds: what a
    /// client decodes.
    #[cfg(test)]
    pub fn squares(&self, court: &Court) -> Vec<usize> {
        let (nx, _) = court.squares_xz();
        let [i0, j0, rows, columns] = self.bounds;
        let bytes = STANDARD.decode(&self.bits).expect("valid base64");
        (0..rows * columns)
            .filter(|&bit| bytes[bit / 8] & (1 << (bit % 8)) != 0)
            .map(|bit| (i0 + bit / columns) * nx + j0 + bit % columns)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate(court: &Court, square: usize) -> Candidate {
        Candidate {
            cell: court.square_centre(square).to_array(),
            c_o: 3.0,
            beyond_horizon: false,
            c_d: 1.0,
            success: 0.5,
        }
    }

    #[test]
    fn the_bitmap_holds_exactly_the_safe_squares() {
        let court = Court::default();
        let (nx, nz) = court.squares_xz();
        // A scattered set: every square whose index is 1 mod 7, plus both far corners.
        let mut safe: Vec<usize> = (0..nx * nz).filter(|s| s % 7 == 1).collect();
        safe.extend([0, nx * nz - 1]);
        safe.sort_unstable();
        let candidates: Vec<Candidate> = safe.iter().map(|&s| candidate(&court, s)).collect();
        let wire = SafeSquares::of(&court, &candidates).unwrap();
        assert_eq!(wire.bounds, [0, 0, nz, nx]);
        assert_eq!(wire.squares(&court), safe);
        // The whole court fits in 140 characters.
        assert_eq!(wire.bits.len(), (nx * nz).div_ceil(8).div_ceil(3) * 4);
    }

    #[test]
    fn the_box_is_cut_to_the_safe_squares() {
        let court = Court::default();
        let (nx, _) = court.squares_xz();
        // Two squares: row 3 column 5, and row 4 column 7.
        let safe = [3 * nx + 5, 4 * nx + 7];
        let candidates: Vec<Candidate> = safe.iter().map(|&s| candidate(&court, s)).collect();
        let wire = SafeSquares::of(&court, &candidates).unwrap();
        assert_eq!(wire.bounds, [3, 5, 2, 3]);
        // Bits 0 (row 0, column 0) and 5 (row 1, column 2) of one byte.
        assert_eq!(wire.bits, STANDARD.encode([0b10_0001]));
        assert_eq!(wire.squares(&court), safe);
        assert_eq!(SafeSquares::of(&court, &[]), None);
    }
}
