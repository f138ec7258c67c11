//! What a client may send: a token bucket per socket. Every socket kind has one for its
//! messages (bots, spectators and replay viewers alike, since any of them can flood),
//! and the server's frame meter has one for frames that are not messages. A bot's
//! budget is its seat's, kept by the [`MatchDriver`](crate::driver::MatchDriver), which
//! alone knows which of its commands answer a perception (those pass free).
//!
//! Time is handed in, as a [`Duration`] since whatever start the caller measures from
//! (the same one every call): the driver's match time, or a socket's age.

use std::time::Duration;

/// A token bucket: `rate` a second sustained, `burst` at once.
#[derive(Debug)]
pub struct Bucket {
    tokens: f64,
    rate: f64,
    burst: f64,
    last: Duration,
    /// Refusals with no quiet second between them.
    strikes: u32,
    last_refused: Duration,
}

impl Bucket {
    /// A full bucket at `now`.
    pub fn new(rate: f64, burst: f64, now: Duration) -> Bucket {
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
    fn refill(&mut self, now: Duration) {
        let accrued = now.saturating_sub(self.last).as_secs_f64() * self.rate;
        self.tokens = (self.tokens + accrued).min(self.burst);
        self.last = self.last.max(now);
    }

    /// The whole tokens there are at `now`, taking none.
    pub fn available(&mut self, now: Duration) -> u64 {
        self.refill(now);
        self.tokens.max(0.0).floor() as u64
    }

    /// Takes up to `wanted` tokens at `now`, as many as there are; returns how many.
    pub fn take_up_to(&mut self, wanted: u64, now: Duration) -> u64 {
        self.refill(now);
        let granted = (self.tokens.max(0.0).floor() as u64).min(wanted);
        self.tokens -= granted as f64;
        granted
    }

    /// Takes a token at `now` if there is one.
    pub fn take(&mut self, now: Duration) -> bool {
        self.refill(now);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            return true;
        }
        if now.saturating_sub(self.last_refused) > Duration::from_secs(1) {
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
    Refuse {
        /// Whether this is the first refusal of a run (the client is told once).
        warn: bool,
    },
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
    /// A full budget at `now`.
    pub fn new(messages_per_second: u32, burst: u32, now: Duration) -> MessageBudget {
        MessageBudget {
            bucket: Bucket::new(f64::from(messages_per_second), f64::from(burst), now),
            burst,
        }
    }

    /// Charges one message at `now`.
    pub fn charge(&mut self, now: Duration) -> Verdict {
        if self.bucket.take(now) {
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
    use super::{Bucket, MessageBudget, Verdict};
    use std::time::Duration;

    const T0: Duration = Duration::ZERO;

    fn ms(ms: u64) -> Duration {
        Duration::from_millis(ms)
    }

    #[test]
    fn a_burst_is_taken_then_refused_once_with_a_warning_then_flooding() {
        let mut budget = MessageBudget::new(1, 5, T0);
        for _ in 0..5 {
            assert_eq!(budget.charge(T0), Verdict::Take);
        }
        assert_eq!(budget.charge(T0), Verdict::Refuse { warn: true });
        for _ in 0..4 {
            assert_eq!(budget.charge(T0), Verdict::Refuse { warn: false });
        }
        assert_eq!(budget.charge(T0), Verdict::Flooding);
    }

    #[test]
    fn tokens_accrue_at_the_rate_up_to_the_burst_and_a_quiet_second_forgives() {
        let mut bucket = Bucket::new(10.0, 4.0, T0);
        assert_eq!(bucket.take_up_to(100, T0), 4);
        assert!(!bucket.take(T0));
        // 10 a second: one token each 100 ms, never more than the burst.
        assert_eq!(bucket.available(ms(250)), 2);
        assert_eq!(bucket.available(ms(60_000)), 4);
        let mut budget = MessageBudget::new(1, 2, T0);
        assert_eq!(budget.charge(T0), Verdict::Take);
        assert_eq!(budget.charge(T0), Verdict::Take);
        assert_eq!(budget.charge(T0), Verdict::Refuse { warn: true });
        assert_eq!(budget.charge(ms(100)), Verdict::Refuse { warn: false });
        // More than a second without a refusal starts a new run (warned again), and
        // a token has accrued meanwhile.
        assert_eq!(budget.charge(ms(1_500)), Verdict::Take);
        assert_eq!(budget.charge(ms(1_500)), Verdict::Refuse { warn: true });
    }

    #[test]
    fn time_going_backwards_takes_no_tokens_back() {
        let mut bucket = Bucket::new(10.0, 4.0, ms(1_000));
        assert_eq!(bucket.take_up_to(4, ms(1_000)), 4);
        assert_eq!(bucket.available(ms(500)), 0);
        assert_eq!(bucket.available(ms(1_100)), 1);
    }
}
