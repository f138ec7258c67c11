//! HTTP byte ranges (RFC 9110 §14): one range of a download, so a client can resume a
//! large replay where it stopped instead of starting again.

/// What a request's `Range` header asks of a file of `len` bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wanted {
    /// The whole file (no header, or one this server does not serve, like several
    /// ranges or another unit: the RFC lets a server answer those with the whole).
    Whole,
    /// Bytes `start..=end`.
    Part {
        /// The first byte's offset.
        start: u64,
        /// The last byte's offset (inclusive).
        end: u64,
    },
    /// A range entirely past the end: 416.
    Unsatisfiable,
}

/// Reads `bytes=a-b`, `bytes=a-` and `bytes=-n`.
pub fn wanted(header: Option<&str>, len: u64) -> Wanted {
    let Some(spec) = header.and_then(|h| h.trim().strip_prefix("bytes=")) else {
        return Wanted::Whole;
    };
    let Some((first, last)) = spec.trim().split_once('-') else {
        return Wanted::Whole;
    };
    let number = |s: &str| {
        let s = s.trim();
        (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            .then(|| s.parse::<u64>().ok())
            .flatten()
    };
    match (first.trim().is_empty(), number(first), number(last)) {
        // The last n bytes.
        (true, _, Some(n)) => {
            if n == 0 || len == 0 {
                Wanted::Unsatisfiable
            } else {
                Wanted::Part {
                    start: len.saturating_sub(n),
                    end: len - 1,
                }
            }
        }
        (false, Some(start), end) if end.is_some() || last.trim().is_empty() => {
            if end.is_some_and(|e| e < start) {
                return Wanted::Whole; // not a valid range: ignored
            }
            if start >= len {
                return Wanted::Unsatisfiable;
            }
            Wanted::Part {
                start,
                end: end.map_or(len - 1, |e| e.min(len - 1)),
            }
        }
        _ => Wanted::Whole,
    }
}

#[cfg(test)]
mod tests {
    use super::{wanted, Wanted};

    #[test]
    fn ranges_are_read_as_the_rfc_writes_them() {
        let part = |start, end| Wanted::Part { start, end };
        let w = |h: &str| wanted(Some(h), 100);
        assert_eq!(wanted(None, 100), Wanted::Whole);
        assert_eq!(w("bytes=0-9"), part(0, 9));
        assert_eq!(w("bytes=90-"), part(90, 99));
        assert_eq!(w("bytes=90-1000"), part(90, 99));
        assert_eq!(w("bytes=-10"), part(90, 99));
        assert_eq!(w("bytes=-1000"), part(0, 99));
        assert_eq!(w("bytes=100-"), Wanted::Unsatisfiable);
        assert_eq!(w("bytes=-0"), Wanted::Unsatisfiable);
        assert_eq!(wanted(Some("bytes=0-"), 0), Wanted::Unsatisfiable);
        // What is not one valid range of bytes is ignored: the whole file.
        for ignored in [
            "bytes=5-2",
            "items=0-9",
            "bytes=0-1,5-6",
            "bytes=a-b",
            "bytes=-",
            "bytes=+1-2",
        ] {
            assert_eq!(w(ignored), Wanted::Whole, "{ignored}");
        }
    }
}
