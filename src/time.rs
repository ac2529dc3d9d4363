//! Message timestamps as VRPN carries them: a `struct timeval` of seconds and microseconds
//! since the Unix epoch.
//!
//! On the wire the seconds are the low 32 bits of `time_t`. We keep them in an
//! `i64`; header seconds are decoded as unsigned 32-bit (what a 64-bit C++ peer does) and
//! payload timevals as signed.
//!
//! # Range and saturation
//!
//! Arithmetic on [`TimeVal`] never overflows and never panics: results are clamped to
//! [`TimeVal::MIN`]`..=`[`TimeVal::MAX`], ±2^62 µs (about ±146,000 years), far beyond any time a
//! message can carry yet small enough that the sum or difference of two such times fits an
//! `i64` of microseconds. Float seconds are converted the same way: `±∞` and finite values
//! beyond the range saturate, NaN adds nothing (or is refused by the `checked_` forms).
//!
//! Float seconds that become a [`Duration`] (a rate's period, a timeout) go through
//! [`checked_duration`] or [`period_of_rate`], which refuse what no schedule can use — NaN,
//! negative values, anything longer than [`MAX_PERIOD`] — instead of panicking as
//! `Duration::from_secs_f64` does.

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

    /// A reading no earlier than anything read so far in the pass, for the timestamps clock
    /// synchronisation needs on the far side of a read (its bound assumes a reply's `t2` and
    /// `t4` are taken after the bytes arrived). The shell's pass clock reads the clocks again;
    /// a [`Now`] (virtual time) gives itself.
    fn fresh(&self) -> Now {
        self.now()
    }
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

/// Longest period or delay made from float seconds (10^9 s, about 31.7 years): a rate below
/// one report per `MAX_PERIOD` is refused, since no schedule of that length means anything
/// and `Instant` arithmetic on longer ones could overflow.
pub const MAX_PERIOD: Duration = Duration::from_secs(1_000_000_000);

/// Float seconds as a [`Duration`], or `None` for NaN, a negative value or more than
/// [`MAX_PERIOD`] (where `Duration::from_secs_f64` would panic or a deadline overflow).
pub fn checked_duration(secs: f64) -> Option<Duration> {
    if secs >= 0.0 && secs <= MAX_PERIOD.as_secs_f64() {
        Some(Duration::from_secs_f64(secs))
    } else {
        None
    }
}

/// The period of `rate` events per second, or `None` unless the rate is finite and at least
/// one per [`MAX_PERIOD`] (within a millionth, so that `1e-9` read in single precision
/// counts). A very high rate gives a zero period (due at every pass).
pub fn period_of_rate(rate: f64) -> Option<Duration> {
    if !(rate.is_finite() && rate > 0.0) {
        return None;
    }
    let period = 1.0 / rate;
    let longest = MAX_PERIOD.as_secs_f64();
    (period <= longest * (1.0 + 1e-6)).then(|| Duration::from_secs_f64(period.min(longest)))
}

/// `at + d`, or the latest instant that can be represented on the way there (for timeouts
/// given by a caller; never panics).
pub fn instant_after(at: Instant, d: Duration) -> Instant {
    at.checked_add(d)
        .or_else(|| at.checked_add(d.min(MAX_PERIOD)))
        .unwrap_or(at)
}

/// Microseconds a [`TimeVal`] may be away from the epoch (2^62 − 1, about 146,000 years): the
/// difference of any two such times fits an `i64`.
pub const MAX_MICROS: i64 = (1 << 62) - 1;

/// A point in time as VRPN messages carry it.
///
/// Arithmetic saturates at [`TimeVal::MIN`] and [`TimeVal::MAX`] (see the
/// [module documentation](self)).
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

    /// The latest time: [`MAX_MICROS`] after the epoch.
    pub const MAX: TimeVal = TimeVal {
        sec: MAX_MICROS / 1_000_000,
        usec: MAX_MICROS % 1_000_000,
    };

    /// The earliest time: [`MAX_MICROS`] before the epoch.
    pub const MIN: TimeVal = TimeVal {
        sec: -(MAX_MICROS / 1_000_000) - 1,
        usec: 1_000_000 - MAX_MICROS % 1_000_000,
    };

    /// Builds a normalised time value (saturating at [`TimeVal::MIN`]/[`TimeVal::MAX`]).
    pub fn new(sec: i64, usec: i64) -> TimeVal {
        TimeVal::from_micros(sec.saturating_mul(1_000_000).saturating_add(usec))
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
            shift => TimeVal::from_micros(read.as_micros().saturating_add(shift)),
        }
    }

    /// Seconds as a float, the form `--json` output and most applications want.
    pub fn as_secs_f64(&self) -> f64 {
        self.sec as f64 + self.usec as f64 * 1e-6
    }

    /// Builds a time value from float seconds (rounded to the microsecond), saturating at
    /// [`TimeVal::MIN`]/[`TimeVal::MAX`]; NaN gives [`TimeVal::ZERO`]. See
    /// [`checked_from_secs_f64`](Self::checked_from_secs_f64) to refuse such values instead.
    pub fn from_secs_f64(secs: f64) -> TimeVal {
        let sec = secs.floor();
        let usec = ((secs - sec) * 1e6).round();
        // `as` saturates (NaN gives 0); `new` saturates the rest.
        TimeVal::new(sec as i64, usec as i64)
    }

    /// Float seconds as a time value, or `None` for NaN and for values beyond
    /// [`TimeVal::MIN`]`..=`[`TimeVal::MAX`].
    pub fn checked_from_secs_f64(secs: f64) -> Option<TimeVal> {
        let limit = MAX_MICROS as f64 * 1e-6;
        (secs.abs() <= limit).then(|| TimeVal::from_secs_f64(secs))
    }

    /// Total microseconds, handy for differences (within ±[`MAX_MICROS`] for any value, so the
    /// sum or difference of two never overflows).
    #[inline]
    pub fn as_micros(&self) -> i64 {
        self.sec
            .saturating_mul(1_000_000)
            .saturating_add(self.usec)
            .clamp(-MAX_MICROS, MAX_MICROS)
    }

    /// Builds a time value from total microseconds (saturating at ±[`MAX_MICROS`]).
    #[inline]
    pub fn from_micros(us: i64) -> TimeVal {
        let us = us.clamp(-MAX_MICROS, MAX_MICROS);
        TimeVal {
            sec: us.div_euclid(1_000_000),
            usec: us.rem_euclid(1_000_000),
        }
    }

    /// `self - earlier` in seconds (negative when `earlier` is later).
    pub fn seconds_since(&self, earlier: TimeVal) -> f64 {
        self.as_micros().saturating_sub(earlier.as_micros()) as f64 * 1e-6
    }

    /// Adds float seconds (rounded to the microsecond), saturating; NaN adds nothing.
    pub fn plus_secs(&self, secs: f64) -> TimeVal {
        // `as` saturates (NaN gives 0).
        let add = (secs * 1e6).round() as i64;
        TimeVal::from_micros(self.as_micros().saturating_add(add))
    }

    /// Adds a duration, saturating.
    pub fn plus(&self, d: Duration) -> TimeVal {
        let add = i64::try_from(d.as_micros()).unwrap_or(i64::MAX);
        TimeVal::from_micros(self.as_micros().saturating_add(add))
    }

    /// Whether a message header carries this time as it is: from the epoch to 2106-02-07
    /// (unsigned 32-bit seconds). APIs that take a time from outside (the Python and C
    /// bindings) refuse any other; [`to_wire`](Self::to_wire) saturates it.
    pub fn fits_header(&self) -> bool {
        (0..=i64::from(u32::MAX)).contains(&self.sec) && (0..1_000_000).contains(&self.usec)
    }

    /// The two 32-bit words sent on the wire. A header holds unsigned seconds (1970 to
    /// 2106): a time before or after is sent as the nearest end of that range.
    #[inline]
    pub fn to_wire(&self) -> (u32, u32) {
        (
            self.sec.clamp(0, i64::from(u32::MAX)) as u32,
            self.usec as u32,
        )
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
    fn arithmetic_saturates_instead_of_overflowing() {
        assert_eq!(TimeVal::MAX.as_micros(), MAX_MICROS);
        assert_eq!(TimeVal::MIN.as_micros(), -MAX_MICROS);
        assert_eq!(TimeVal::from_micros(MAX_MICROS), TimeVal::MAX);
        assert_eq!(TimeVal::from_micros(-MAX_MICROS), TimeVal::MIN);
        assert_eq!(TimeVal::from_micros(i64::MIN), TimeVal::MIN);
        assert_eq!(TimeVal::new(i64::MAX, 999_999), TimeVal::MAX);
        assert_eq!(TimeVal::new(i64::MIN, -1), TimeVal::MIN);
        let odd = TimeVal {
            sec: i64::MAX,
            usec: i64::MAX,
        };
        assert_eq!(odd.as_micros(), MAX_MICROS);
        assert!(TimeVal::MAX.seconds_since(TimeVal::MIN) > 9.2e12);
        let t = TimeVal::new(1_700_000_000, 5);
        assert_eq!(t.plus_secs(1e14), TimeVal::MAX);
        assert_eq!(t.plus_secs(1e300), TimeVal::MAX);
        assert_eq!(t.plus_secs(f64::INFINITY), TimeVal::MAX);
        assert_eq!(t.plus_secs(f64::NEG_INFINITY), TimeVal::MIN);
        assert_eq!(t.plus_secs(f64::NAN), t);
        assert_eq!(t.plus_secs(1.5), TimeVal::new(1_700_000_001, 500_005));
        assert_eq!(TimeVal::MAX.plus_secs(1.0), TimeVal::MAX);
        assert_eq!(t.plus(Duration::MAX), TimeVal::MAX);
        assert_eq!(TimeVal::MAX.plus(Duration::from_secs(1)), TimeVal::MAX);
        assert_eq!(TimeVal::from_secs_f64(1e300), TimeVal::MAX);
        assert_eq!(TimeVal::from_secs_f64(-1e300), TimeVal::MIN);
        assert_eq!(TimeVal::from_secs_f64(f64::NAN), TimeVal::ZERO);
        assert_eq!(TimeVal::from_secs_f64(2.25), TimeVal::new(2, 250_000));
        assert_eq!(TimeVal::checked_from_secs_f64(1e300), None);
        assert_eq!(TimeVal::checked_from_secs_f64(f64::NAN), None);
        assert_eq!(
            TimeVal::checked_from_secs_f64(-0.5),
            Some(TimeVal::new(-1, 500_000))
        );
    }

    #[test]
    fn wire_seconds_saturate_to_what_a_header_holds() {
        assert_eq!(TimeVal::MAX.to_wire().0, u32::MAX);
        assert_eq!(TimeVal::new(1 << 33, 7).to_wire(), (u32::MAX, 7));
        assert_eq!(TimeVal::new(-1, 0).to_wire(), (0, 0));
        assert_eq!(TimeVal::new(1_700_000_000, 9).to_wire(), (1_700_000_000, 9));
        assert!(TimeVal::new(u32::MAX.into(), 999_999).fits_header());
        assert!(TimeVal::ZERO.fits_header());
        assert!(!TimeVal::new(1 << 32, 0).fits_header());
        assert!(!TimeVal::new(-1, 999_999).fits_header());
        assert!(!TimeVal { sec: 5, usec: -1 }.fits_header());
    }

    #[test]
    fn float_durations_are_checked() {
        assert_eq!(checked_duration(0.25), Some(Duration::from_millis(250)));
        assert_eq!(checked_duration(0.0), Some(Duration::ZERO));
        assert_eq!(checked_duration(1e9), Some(Duration::from_secs_f64(1e9)));
        for bad in [-1e-9, 1e9 + 1.0, 1e30, f64::INFINITY, f64::NAN, -0.0 - 1.0] {
            assert_eq!(checked_duration(bad), None, "{bad}");
        }
        assert_eq!(period_of_rate(4.0), Some(Duration::from_millis(250)));
        let about_max = |d: Option<Duration>| {
            d.is_some_and(|d| d.max(MAX_PERIOD) - d.min(MAX_PERIOD) < Duration::from_micros(1))
        };
        assert!(about_max(period_of_rate(1e-9)));
        let single = f64::from(1e-9f32); // a hair below 1e-9
        assert!(about_max(period_of_rate(single)));
        assert_eq!(period_of_rate(1e300), Some(Duration::ZERO));
        for bad in [1e-20, 5e-20, 9.9e-10, 0.0, -1.0, f64::INFINITY, f64::NAN] {
            assert_eq!(period_of_rate(bad), None, "{bad}");
        }
        let t = Instant::now();
        assert_eq!(
            instant_after(t, Duration::from_secs(1)),
            t + Duration::from_secs(1)
        );
        assert!(instant_after(t, Duration::MAX) >= t + MAX_PERIOD);
    }

    #[test]
    fn header_seconds_are_unsigned() {
        let t = TimeVal::from_header_words(0xFFFF_FFFF, 5);
        assert_eq!(t.sec, 4_294_967_295);
        assert_eq!(t.to_wire(), (0xFFFF_FFFF, 5));
    }
}
