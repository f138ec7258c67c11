//! What a client may send: a token bucket per socket. Every socket kind has one for its
//! messages (bots, spectators and replay viewers alike, since any of them can flood),
//! and the frame meter has one for frames that are not messages.

use std::time::{Duration, Instant};

/// A token bucket: `rate` a second sustained, `burst` at once.
#[derive(Debug)]
pub struct Bucket {
    tokens: f64,
    rate: f64,
    burst: f64,
    last: Instant,
    /// Refusals with no quiet second between them.
    strikes: u32,
    last_refused: Instant,
}

impl Bucket {
    pub fn new(rate: f64, burst: f64) -> Bucket {
        let now = Instant::now();
        Bucket {
            tokens: burst,
            rate,
            burst,
            last: now,
            strikes: 0,
            last_refused: now,
        }
    }

    /// Adds what has accrued since the last look, up to the burst.
    fn refill(&mut self, now: Instant) {
        self.tokens = (self.tokens + (now - self.last).as_secs_f64() * self.rate).min(self.burst);
        self.last = now;
    }

    /// The whole tokens there are, taking none.
    pub fn available(&mut self) -> u64 {
        self.refill(Instant::now());
        self.tokens.max(0.0).floor() as u64
    }

    /// Takes up to `wanted` tokens, as many as there are; returns how many.
    pub fn take_up_to(&mut self, wanted: u64) -> u64 {
        self.refill(Instant::now());
        let granted = (self.tokens.max(0.0).floor() as u64).min(wanted);
        self.tokens -= granted as f64;
        granted
    }

    /// Takes a token if there is one.
    pub fn take(&mut self) -> bool {
        let now = Instant::now();
        self.refill(now);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            return true;
        }
        if now - self.last_refused > Duration::from_secs(1) {
            self.strikes = 0;
        }
        self.strikes += 1;
        self.last_refused = now;
        false
    }
}

/// What to do with a message, by its sender's budget.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Within budget: handle it.
    Take,
    /// Over budget: drop it; `warn` the first time in a run of refusals.
    Refuse { warn: bool },
    /// Refused more than a burst of messages with no quiet second: close with 1008.
    Flooding,
}

/// A socket's message budget: `messages_per_second` sustained and `burst` at once; a
/// client that goes on sending a whole burst past it is flooding.
#[derive(Debug)]
pub struct MessageBudget {
    bucket: Bucket,
    burst: u32,
}

impl MessageBudget {
    pub fn new(messages_per_second: u32, burst: u32) -> MessageBudget {
        MessageBudget {
            bucket: Bucket::new(f64::from(messages_per_second), f64::from(burst)),
            burst,
        }
    }

    pub fn charge(&mut self) -> Verdict {
        if self.bucket.take() {
            Verdict::Take
        } else if self.bucket.strikes > self.burst {
            Verdict::Flooding
        } else {
            Verdict::Refuse {
                warn: self.bucket.strikes == 1,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{MessageBudget, Verdict};

    #[test]
    fn a_burst_is_taken_then_refused_once_with_a_warning_then_flooding() {
        let mut budget = MessageBudget::new(1, 5);
        for _ in 0..5 {
            assert_eq!(budget.charge(), Verdict::Take);
        }
        assert_eq!(budget.charge(), Verdict::Refuse { warn: true });
        for _ in 0..4 {
            assert_eq!(budget.charge(), Verdict::Refuse { warn: false });
        }
        assert_eq!(budget.charge(), Verdict::Flooding);
    }
}
