//! Message timestamps as VRPN carries them: a `struct timeval` of seconds and microseconds
//! since the Unix epoch.
//!
//! On the wire the seconds are the low 32 bits of `time_t`. We keep them in an
//! `i64` so arithmetic never overflows; header seconds are decoded as unsigned 32-bit (what a
//! 64-bit C++ peer does) and payload timevals as signed.

use std::sync::atomic::{AtomicI64, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Microseconds added to every wall-clock reading of this process (see [`shift_wall_clock`]).
static WALL_CLOCK_SHIFT_US: AtomicI64 = AtomicI64::new(0);

/// Makes this process's wall clock read `seconds` ahead of the system's (behind when
/// negative), as a host whose clock is off would: every message this process stamps from
/// then on carries the shifted time. For tests and demonstrations of clock synchronisation
/// (`vrpn_server -clockshift SECONDS`); the monotonic clock that orders deadlines is not
/// touched.
pub fn shift_wall_clock(seconds: f64) {
    let us = if seconds.is_finite() {
        (seconds * 1e6).round() as i64
    } else {
        0
    };
    WALL_CLOCK_SHIFT_US.store(us, Ordering::Relaxed);
}

/// One reading of both clocks, taken once per loop pass by the shell (or by a test's virtual
/// clock) and passed down to everything below it.
///
/// `mono` orders deadlines and never jumps; `wall` is what messages carry (C++ stamps with
/// `gettimeofday`). Keeping both from one reading lets a test drive a whole client and server
/// through every time-out on a virtual clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Now {
    /// Monotonic time, for deadlines.
    pub mono: Instant,
    /// Wall-clock time, for message timestamps.
    pub wall: TimeVal,
}

/// Where a time comes from, for calls that need it only on some paths: a [`Now`] gives itself
/// (tests, virtual time); the shell's per-pass clock reads the system clocks the first time it
/// is asked and then answers the same reading for the rest of the pass, so a loop pass that
/// only moves messages reads no clock at all.
pub trait TimeSource {
    /// The time.
    fn now(&self) -> Now;
}

impl TimeSource for Now {
    fn now(&self) -> Now {
        *self
    }
}

impl Now {
    /// Both clocks, read now. Only the I/O shell and the programs call this; everything else is
    /// handed a `Now`.
    pub fn read() -> Now {
        Now {
            mono: Instant::now(),
            wall: TimeVal::now(),
        }
    }

    /// The same moment moved `d` later on both clocks (virtual time in tests).
    pub fn plus(&self, d: Duration) -> Now {
        Now {
            mono: self.mono + d,
            wall: self.wall.plus(d),
        }
    }

    /// Seconds from `earlier` to `self` on the monotonic clock (0 when `earlier` is later).
    pub fn secs_since(&self, earlier: Instant) -> f64 {
        self.mono.saturating_duration_since(earlier).as_secs_f64()
    }
}

/// A point in time as VRPN messages carry it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TimeVal {
    /// Whole seconds since 1970-01-01 UTC.
    pub sec: i64,
    /// Microseconds, 0..=999_999 once normalised.
    pub usec: i64,
}

impl TimeVal {
    /// The zero time (what C++ devices stamp before their first report).
    pub const ZERO: TimeVal = TimeVal { sec: 0, usec: 0 };

    /// Builds a normalised time value.
    pub fn new(sec: i64, usec: i64) -> TimeVal {
        TimeVal { sec, usec }.normalised()
    }

    /// The current wall-clock time, as C++ `vrpn_gettimeofday` reads it (moved by
    /// [`shift_wall_clock`] when a test asked for that).
    pub fn now() -> TimeVal {
        // `clock_gettime` straight into seconds and microseconds: `SystemTime` would go through
        // a `Duration` (a subtraction with carries, then a division), which doubled the cost of
        // the one clock reading a pass that receives reports makes.
        #[allow(clippy::useless_conversion)] // `time_t` and `c_long` are narrower on some targets
        let read = match nix::time::clock_gettime(nix::time::ClockId::CLOCK_REALTIME) {
            Ok(t) if t.tv_sec() >= 0 => TimeVal {
                sec: i64::from(t.tv_sec()),
                usec: i64::from(t.tv_nsec()) / 1000,
            },
            _ => {
                let d = SystemTime::now()
                    .duration_since(UNIX_EPOCH)
                    .unwrap_or(Duration::ZERO);
                TimeVal {
                    sec: d.as_secs() as i64,
                    usec: d.subsec_micros() as i64,
                }
            }
        };
        match WALL_CLOCK_SHIFT_US.load(Ordering::Relaxed) {
            0 => read,
            shift => TimeVal::from_micros(read.as_micros() + shift),
        }
    }

    /// Seconds as a float, the form `--json` output and most applications want.
    pub fn as_secs_f64(&self) -> f64 {
        self.sec as f64 + self.usec as f64 * 1e-6
    }

    /// Builds a time value from float seconds (rounded to the microsecond).
    pub fn from_secs_f64(secs: f64) -> TimeVal {
        let sec = secs.floor();
        let usec = ((secs - sec) * 1e6).round();
        TimeVal::new(sec as i64, usec as i64)
    }

    /// Total microseconds, handy for differences.
    pub fn as_micros(&self) -> i64 {
        self.sec * 1_000_000 + self.usec
    }

    /// Builds a time value from total microseconds.
    pub fn from_micros(us: i64) -> TimeVal {
        TimeVal::new(us.div_euclid(1_000_000), us.rem_euclid(1_000_000))
    }

    /// `self - earlier` in seconds (negative when `earlier` is later).
    pub fn seconds_since(&self, earlier: TimeVal) -> f64 {
        (self.as_micros() - earlier.as_micros()) as f64 * 1e-6
    }

    /// Adds float seconds (rounded to the microsecond).
    pub fn plus_secs(&self, secs: f64) -> TimeVal {
        if !secs.is_finite() {
            return if secs > 0.0 {
                TimeVal::new(i64::MAX / 2_000_000, 0)
            } else {
                *self
            };
        }
        TimeVal::from_micros(self.as_micros() + (secs * 1e6).round() as i64)
    }

    /// Adds a duration.
    pub fn plus(&self, d: Duration) -> TimeVal {
        TimeVal::from_micros(self.as_micros() + d.as_micros() as i64)
    }

    fn normalised(self) -> TimeVal {
        let total = self.sec * 1_000_000 + self.usec;
        TimeVal {
            sec: total.div_euclid(1_000_000),
            usec: total.rem_euclid(1_000_000),
        }
    }

    /// The two 32-bit words sent on the wire (low 32 bits of the seconds).
    pub fn to_wire(&self) -> (u32, u32) {
        (self.sec as u32, self.usec as u32)
    }

    /// Decodes header words: seconds unsigned (as a 64-bit C++ peer reads them).
    pub fn from_header_words(sec: u32, usec: u32) -> TimeVal {
        TimeVal {
            sec: sec as i64,
            usec: usec as i64,
        }
    }

    /// Decodes a timeval inside a payload: both words signed (`vrpn_unbuffer(timeval)`).
    pub fn from_payload_words(sec: i32, usec: i32) -> TimeVal {
        TimeVal {
            sec: sec as i64,
            usec: usec as i64,
        }
    }
}

impl std::fmt::Display for TimeVal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{:06}", self.sec, self.usec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalises_and_round_trips_micros() {
        let t = TimeVal::new(10, 1_500_000);
        assert_eq!(
            t,
            TimeVal {
                sec: 11,
                usec: 500_000
            }
        );
        assert_eq!(TimeVal::from_micros(t.as_micros()), t);
        let neg = TimeVal::from_micros(-1);
        assert_eq!(
            neg,
            TimeVal {
                sec: -1,
                usec: 999_999
            }
        );
        assert!((t.seconds_since(TimeVal::new(10, 0)) - 1.5).abs() < 1e-12);
    }

    #[test]
    fn header_seconds_are_unsigned() {
        let t = TimeVal::from_header_words(0xFFFF_FFFF, 5);
        assert_eq!(t.sec, 4_294_967_295);
        assert_eq!(t.to_wire(), (0xFFFF_FFFF, 5));
    }
}
