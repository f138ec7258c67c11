//! A match's place among the `max_matches` a server runs at once. Counting the running
//! matches and then inserting one were two steps, so a burst of requests could all see
//! room and all start; a place is now taken in one atomic step before anything is
//! built, and given back when its owner, the match task, is dropped — however the task
//! ends, a panic included — so no path can forget to give it back.

use super::metrics::Metrics;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;

/// A place taken; the `fieldhouse_matches` gauge counts them.
pub struct Slot(Arc<Metrics>);

impl Slot {
    /// Takes a place if fewer than `max` are taken.
    pub fn reserve(metrics: &Arc<Metrics>, max: usize) -> Option<Slot> {
        metrics
            .matches_running
            .fetch_update(Relaxed, Relaxed, |n| (n < max as u64).then_some(n + 1))
            .ok()
            .map(|_| Slot(metrics.clone()))
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.matches_running.fetch_sub(1, Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::Slot;
    use std::sync::atomic::Ordering::Relaxed;
    use std::sync::{Arc, Barrier};

    #[test]
    fn racing_reservations_take_exactly_the_places_there_are() {
        let metrics = Arc::default();
        let (max, racers) = (5, 64);
        let start = Arc::new(Barrier::new(racers));
        let taken: Vec<Option<Slot>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..racers)
                .map(|_| {
                    let (metrics, start) = (&metrics, start.clone());
                    s.spawn(move || {
                        start.wait();
                        Slot::reserve(metrics, max)
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert_eq!(taken.iter().flatten().count(), max);
        assert_eq!(metrics.matches_running.load(Relaxed), max as u64);
        drop(taken);
        assert_eq!(
            metrics.matches_running.load(Relaxed),
            0,
            "every place given back"
        );
        assert!(Slot::reserve(&metrics, max).is_some());
    }
}
