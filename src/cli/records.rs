//! Progress of a long run as one-line records on stderr, for when stderr is not a terminal (a script,
//! a CI log, `nohup`, a worker's log), where a progress bar would print nothing or garbage. On a
//! terminal the commands draw their bars instead.
//!
//! A record reads `progress: WHAT; elapsed 1 min 4 s, eta 2 min 10 s`. The first one is printed at
//! once, then at most one every [`INTERVAL`], and the last when the work is done, so that a log shows
//! the run started, moves, and ended, without flooding.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// The shortest time between two records (apart from the last).
pub(crate) const INTERVAL: Duration = Duration::from_secs(10);

/// The records of one run.
pub(crate) struct Records {
    start: Instant,
    last: Option<Instant>,
}

impl Records {
    /// Records for a run starting now, or `None` when stderr is a terminal (the bars show progress).
    pub(crate) fn new() -> Option<Self> {
        (!std::io::stderr().is_terminal()).then(|| Self {
            start: Instant::now(),
            last: None,
        })
    }

    /// `what` has been reached, `done` of `total` units of work (iterations, seconds of budget):
    /// prints its record if it is the first, the last (`done >= total`) or [`INTERVAL`] after the
    /// previous one. The ETA assumes the remaining work goes at the pace so far.
    pub(crate) fn record(&mut self, done: f64, total: f64, what: impl FnOnce() -> String) {
        let now = Instant::now();
        let finished = done >= total;
        if !finished && self.last.is_some_and(|t| now - t < INTERVAL) {
            return;
        }
        self.last = Some(now);
        let elapsed = (now - self.start).as_secs_f64();
        let eta = match done > 0.0 {
            true => duration((elapsed * (total - done).max(0.0) / done).round()),
            false => "unknown".to_string(),
        };
        eprintln!(
            "progress: {}; elapsed {}, eta {eta}",
            what(),
            duration(elapsed)
        );
    }
}

/// `12.3 s`, `4 min 5 s`, `1 h 2 min`.
fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0);
    if s < 60.0 {
        return format!("{s:.1} s");
    }
    let whole = s.round() as u64;
    match whole < 3600 {
        true => format!("{} min {} s", whole / 60, whole % 60),
        false => format!("{} h {} min", whole / 3600, whole % 3600 / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::duration;

    #[test]
    fn durations_read_as_a_person_writes_them() {
        assert_eq!(duration(0.04), "0.0 s");
        assert_eq!(duration(12.34), "12.3 s");
        assert_eq!(duration(245.4), "4 min 5 s");
        assert_eq!(duration(3725.0), "1 h 2 min");
    }
}
