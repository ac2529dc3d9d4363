//! Translating a peer's timestamps with a fixed estimate: the per-message path, kept free of
//! divisions and floating-point work for fresh timestamps.

use std::time::Duration;

use crate::time::TimeVal;

/// A time value as microseconds, wide enough that no sum or difference overflows.
pub(super) fn micros(t: TimeVal) -> i128 {
    t.sec as i128 * 1_000_000 + t.usec as i128
}

/// How long a [`Translation`] may be reused before it is worked out again (see
/// [`ClockSync::translation_until`](super::ClockSync::translation_until)).
pub const TRANSLATION_REUSE: Duration = Duration::from_millis(250);

/// Peer-to-local time translation fixed at one moment (see
/// [`ClockSync::translation`](super::ClockSync::translation)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Translation {
    /// The offset at that moment, in microseconds, and split into seconds and microseconds
    /// (0..1_000_000) so that translating needs no division.
    pub(super) offset_us: i64,
    offset_sec: i64,
    offset_usec: i64,
    /// That moment on the local wall clock, in microseconds.
    pub(super) now_us: i64,
    /// Drift of the offset, seconds per second.
    pub(super) drift: f64,
    /// Timestamps at most this many microseconds old (or ahead) move by less than half a
    /// microsecond of drift, so they skip the floating-point step (which for a live stream,
    /// whose timestamps are fresh, is nearly always).
    pub(super) drift_free_age_us: i64,
}

impl Translation {
    pub(super) fn new(offset_us: i64, now_us: i64, drift: f64) -> Translation {
        // |drift × age| < 0.5 for every |age| ≤ 0.5 / |drift|; the margin keeps the
        // floating-point product (relative error ~1e-16) below one half as well.
        let drift_free_age_us = if drift == 0.0 {
            i64::MAX
        } else {
            (0.5 / drift.abs() * (1.0 - 1e-9)).min(i64::MAX as f64 / 2.0) as i64
        };
        Translation {
            offset_us,
            offset_sec: offset_us.div_euclid(1_000_000),
            offset_usec: offset_us.rem_euclid(1_000_000),
            now_us,
            drift,
            drift_free_age_us,
        }
    }

    /// The local time of a peer timestamp: `remote − offset`, the offset taken at the moment
    /// the timestamp refers to (drift applied over its age).
    ///
    /// This runs for every message from a synchronised peer, so it avoids divisions and the
    /// library call behind `f64::round` (halves round away from zero, as `round` does).
    #[inline]
    pub fn remote_to_local(&self, remote: TimeVal) -> TimeVal {
        let remote_us = remote
            .sec
            .saturating_mul(1_000_000)
            .saturating_add(remote.usec);
        let age = self
            .now_us
            .saturating_sub(remote_us.saturating_sub(self.offset_us));
        // The offset was smaller by drift × age when the timestamp was taken.
        let back = if age.unsigned_abs() <= self.drift_free_age_us as u64 {
            0
        } else {
            drift_back(self.drift, age)
        };
        let usec = remote.usec - self.offset_usec + back;
        let sec = remote.sec.saturating_sub(self.offset_sec);
        if (0..1_000_000).contains(&usec) {
            TimeVal { sec, usec }
        } else if (-1_000_000..0).contains(&usec) {
            TimeVal {
                sec: sec.saturating_sub(1),
                usec: usec + 1_000_000,
            }
        } else {
            TimeVal::from_micros(sec.saturating_mul(1_000_000).saturating_add(usec))
        }
    }
}

/// `drift × age` rounded to whole microseconds (halves away from zero, as `f64::round`,
/// without its library call).
fn drift_back(drift: f64, age_us: i64) -> i64 {
    let back = drift * age_us as f64;
    if back >= 0.0 {
        (back + 0.5) as i64
    } else {
        (back - 0.5) as i64
    }
}

/// Microseconds back to a time value, saturating at what `i64` microseconds hold.
pub(super) fn to_timeval(us: i128) -> TimeVal {
    let us = us.clamp(i64::MIN as i128 / 2, i64::MAX as i128 / 2) as i64;
    TimeVal::from_micros(us)
}
