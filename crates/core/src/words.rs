//! How counts and figures read in the text people see: the binary's human-readable
//! output and the load generator's reports. (JSON output keeps every figure at full
//! precision; this is only for lines a person reads.)

/// `n` and the noun, plural unless `n` is 1: `plural(1, "possession")` is "1
/// possession", `plural(3, "pass")` is "3 passes", `plural(2, "bot log entry")` is "2
/// bot log entries". The noun is written in the singular; only its last word changes.
pub fn plural(n: u64, noun: &str) -> String {
    if n == 1 {
        return format!("1 {noun}");
    }
    let ends_like = |suffixes: &[&str]| suffixes.iter().any(|s| noun.ends_with(s));
    let plural = if ends_like(&["s", "x", "z", "ch", "sh"]) {
        format!("{noun}es")
    } else if noun.ends_with('y') && !ends_like(&["ay", "ey", "oy", "uy"]) {
        format!("{}ies", &noun[..noun.len() - 1])
    } else {
        format!("{noun}s")
    };
    format!("{n} {plural}")
}

/// `x` rounded to at most `decimals` places, without trailing zeros: `figure(2.8166, 2)`
/// is "2.82", `figure(600.0, 2)` is "600", `figure(0.12000000000000001, 3)` is "0.12".
/// A value that rounds to zero is "0", never "-0".
pub fn figure(x: f64, decimals: usize) -> String {
    let mut text = format!("{x:.decimals$}");
    if text.contains('.') {
        let kept = text.trim_end_matches('0').trim_end_matches('.').len();
        text.truncate(kept);
    }
    if text == "-0" {
        text = "0".to_string();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::{figure, plural};

    #[test]
    fn one_is_singular_and_every_other_count_plural() {
        assert_eq!(plural(1, "possession"), "1 possession");
        assert_eq!(plural(0, "possession"), "0 possessions");
        assert_eq!(plural(2, "pass"), "2 passes");
        assert_eq!(plural(1, "pass"), "1 pass");
        assert_eq!(plural(5, "launch"), "5 launches");
        assert_eq!(plural(2, "match"), "2 matches");
        assert_eq!(plural(3, "bot log entry"), "3 bot log entries");
        assert_eq!(plural(3, "day"), "3 days");
        assert_eq!(plural(18001, "frame"), "18001 frames");
    }

    #[test]
    fn figures_are_rounded_and_trimmed() {
        assert_eq!(figure(1941.9166666666667, 2), "1941.92");
        assert_eq!(figure(600.0, 2), "600");
        assert_eq!(figure(0.12000000000000001, 3), "0.12");
        assert_eq!(figure(2.5, 1), "2.5");
        assert_eq!(figure(-0.0001, 2), "0");
        assert_eq!(figure(1500.0, 0), "1500");
        assert_eq!(figure(-3.26, 1), "-3.3");
    }
}
