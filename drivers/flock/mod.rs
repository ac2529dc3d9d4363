//! Ascension Flock of Birds: every receiver on the master bird's serial line
//! ([`FlockProtocol`], run by the shared [`Lifecycle`](crate::driver::Lifecycle)), or one
//! serial line per receiver ([`parallel`]: a group of drivers sharing the Flock's state); the
//! `vrpn.cfg` lines ([`config`]) and a device simulator (`sim`, with the `sim` feature).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Tracker_Flock NAME SENSORS PORT BAUD INVERT [USE_ERT] [HEMISPHERE]
//! vrpn_Tracker_Flock_Parallel NAME SENSORS MASTER_PORT BAUD INVERT PORT_1 … PORT_N
//! ```
//!
//! `SENSORS` receivers (at most 13); `BAUD` must match the master bird's switches; a non-zero
//! `INVERT` reports the inverse quaternion. `USE_ERT` says whether an extended-range
//! transmitter (with its controller at bus address 1) is present: a token starting with `n` or
//! `N` means no, anything else (and the default) yes. `HEMISPHERE` is one of `+x -x +y -y +z
//! -z` (default `+z`). The parallel form always assumes an extended-range transmitter and the
//! `+z` hemisphere, and its receivers' records are never inverted (in C++ the flag reaches
//! only the master, which reports nothing).
//!
//! # What is sent
//!
//! One `vrpn_Tracker Pos_Quat` message (LOW_LATENCY) per record, from the tracker `NAME`,
//! with `SENSORS` sensors: sensor = the receiver's index from 0 (on one line, taken from the
//! record's bus address; in the parallel form, the index of its line), position in metres,
//! quaternion x, y, z, w (see [`record`] for the scaling). Each message carries the time the
//! record's first byte arrived. Resets, time-outs and failures are announced as text messages
//! from `NAME`.
//!
//! # Supervision
//!
//! Opening the port starts the reset ([`reset`]), a state machine over deadlines that ends
//! in stream mode. Records are found byte by byte ([`framer`]): garbage costs at most the
//! record it hits, never a later one. More than [`WATCHDOG`] without a record (or after the
//! reset) sends an error text, and the port is reopened and the Flock reset. A failed reset
//! does the same; after [`FAILURES_BEFORE_PAUSE`] failed attempts in a row (a record sets the
//! count back to 0) the lifecycle sends advice and waits [`RETRY_PAUSE`] before the next.
//!
//! # Differences from C++ VRPN
//!
//! * The reset takes about 0.8 s on a Flock that answers at once, not ≈ 19 s; it waits for
//!   answers instead of sleeping, and it never blocks other devices.
//! * C++ goes back to a full reset after more than one record length of bytes without a
//!   phasing bit; here such bytes are only skipped (and reported at most once a second), and
//!   a stream that stays unreadable is caught by the watchdog.
//! * A group-mode record whose address is not one of the receivers is skipped (C++ would
//!   report it under a sensor number it does not have).

pub mod config;
pub mod framer;
mod notes;
pub mod parallel;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod parallel_tests;
#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::framer::{Framed, Framer};
use self::notes::{say, FailureText};
use self::record::{invert_xyzw, sensor_for_address, PosQuat, Transmitter, GROUP_RECORD_LEN};
use self::reset::{Outcome, Progress, ResetPlan, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::registry::Driver;
use crate::driver::{Cx, Pause, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{Connection, Error, TrackerServer};

pub use self::config::{Flock, FlockParallel};

/// The registry entry: `vrpn_Tracker_Flock` (every receiver on the master's line) and
/// `vrpn_Tracker_Flock_Parallel` (one line per receiver).
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_Flock", "vrpn_Tracker_Flock_Parallel"],
    parse: |line| {
        if line.keyword() == "vrpn_Tracker_Flock_Parallel" {
            config::parse_parallel(line)
        } else {
            config::parse_flock(line)
        }
    },
    hints: &[],
};

pub use self::parallel::FlockParallelPort;

/// Longest gap without a record before the Flock is declared failed and reset (as C++).
pub const WATCHDOG: Duration = Duration::from_secs(2);
/// Failed attempts in a row after which the driver sends advice and pauses.
pub const FAILURES_BEFORE_PAUSE: u32 = 4;
/// The pause after [`FAILURES_BEFORE_PAUSE`] failed attempts (as the C++ parallel Flock).
pub const RETRY_PAUSE: Duration = Duration::from_secs(15);
/// At most one "skipped bytes" note per this interval.
pub const RESYNC_NOTE_INTERVAL: Duration = Duration::from_secs(1);

/// The framework's text when a tracker is given up and reset.
const TRYING_TO_RESET: &str =
    "Tracker failed, trying to reset (Try power cycle if more than 4 attempts made)";
/// Advice after repeated failures.
const ADVICE: &str = "Flock keeps failing: check that every cable is attached, every unit is \
                      switched to FLY and no receiver lies too close to the transmitter, then \
                      power cycle the Flock. Next attempt in 15 seconds";

/// Counts skipped bytes and reports them at most once per [`RESYNC_NOTE_INTERVAL`] (the
/// parallel form's lines share one count).
#[derive(Clone, Debug, Default)]
struct SkipNotes {
    total: u64,
    unreported: u64,
    last_note: Option<Instant>,
}

impl SkipNotes {
    fn add(&mut self, n: u32, now: Instant, tracker: &TrackerServer) {
        self.total += u64::from(n);
        self.unreported += u64::from(n);
        if self.unreported == 0
            || self
                .last_note
                .is_some_and(|t| now < t + RESYNC_NOTE_INTERVAL)
        {
            return;
        }
        say(
            tracker,
            TextSeverity::Warning,
            format_args!(
                "Flock: skipped {} bytes of garbage to find the next record",
                self.unreported
            ),
        );
        self.unreported = 0;
        self.last_note = Some(now);
    }
}

/// An Ascension Flock of Birds with every receiver on the master bird's serial line (group
/// mode, stream mode): the protocol run by the shared [`Lifecycle`](crate::driver::Lifecycle).
pub struct FlockProtocol {
    port: String,
    baud: u32,
    receivers: u8,
    transmitter: Transmitter,
    invert: bool,
    tracker: TrackerServer,
    reset: ResetSequence,
    framer: Framer,
    rate: Option<(u8, f64)>,
}

impl FlockProtocol {
    /// The protocol of a `vrpn_Tracker_Flock` entry, with its tracker (one sensor per
    /// receiver) served on `conn`.
    pub fn new(cfg: &Flock, conn: &Connection) -> Result<FlockProtocol, Error> {
        let receivers = u8::try_from(cfg.sensors)
            .ok()
            .filter(|n| (1..=config::MAX_FLOCK_SENSORS as u8).contains(n))
            .ok_or(Error::Unsupported("a Flock has 1 to 13 receivers"))?;
        let transmitter = Transmitter::from_ert(cfg.use_ert);
        let tracker = TrackerServer::new(&cfg.name, conn, usize::from(receivers))?;
        Ok(FlockProtocol {
            port: cfg.port.clone(),
            baud: cfg.baud,
            receivers,
            transmitter,
            invert: cfg.invert_quaternion,
            tracker,
            reset: ResetSequence::new(ResetPlan {
                receivers,
                transmitter,
                hemisphere: cfg.hemisphere,
                stream: true,
            }),
            framer: Framer::new(GROUP_RECORD_LEN),
            rate: None,
        })
    }

    /// The serial port to open, as the configuration gives it.
    pub fn port(&self) -> &str {
        &self.port
    }

    /// The tracker server the poses go out through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// The reset plan (receivers, transmitter, hemisphere).
    pub fn plan(&self) -> &ResetPlan {
        self.reset.plan()
    }

    /// The crystal speed (MHz) and measurement rate (Hz) the last reset read, if it could.
    pub fn measurement_rate(&self) -> Option<(u8, f64)> {
        self.rate
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Done(outcome) => {
                self.reset_done(outcome, cx);
                Reset::Done
            }
            Progress::Failed(failure) => {
                let units = self.reset.plan().units();
                cx.say(
                    TextSeverity::Error,
                    format_args!("{}", FailureText { failure, units }),
                );
                cx.say(TextSeverity::Error, format_args!("{TRYING_TO_RESET}"));
                Reset::Failed(Retry::Reopen)
            }
        }
    }

    fn reset_done(&mut self, outcome: Outcome, cx: &mut Cx<'_>) {
        self.framer.clear();
        self.rate = outcome.rate;
        match outcome.rate {
            Some((mhz, hz)) => cx.say(
                TextSeverity::Normal,
                format_args!(
                    "Flock reset: {} receivers streaming, measurement rate {hz:.2} Hz \
                     ({mhz} MHz crystal)",
                    self.receivers
                ),
            ),
            None => cx.say(
                TextSeverity::Warning,
                format_args!(
                    "Flock reset: {} receivers streaming; the measurement rate did not arrive",
                    self.receivers
                ),
            ),
        }
    }

    fn record(&mut self, framed: Framed, cx: &mut Cx<'_>) {
        let address = framed.bytes[GROUP_RECORD_LEN - 1];
        let Some(sensor) = sensor_for_address(address, self.receivers, self.transmitter) else {
            self.framer.reject(&framed);
            return;
        };
        cx.skipped(
            u64::from(framed.skipped),
            "Flock",
            format_args!(" (bytes without the phasing bit, or a record cut short)"),
        );
        let r = PosQuat::decode(&framed.bytes);
        let mut quat = r.quat_xyzw();
        if self.invert {
            quat = invert_xyzw(quat);
        }
        cx.record(framed.first_byte);
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.tracker.report_pose(
            sensor,
            framed.first_byte.wall,
            r.position_m(self.transmitter),
            quat,
        );
    }
}

impl Protocol for FlockProtocol {
    const KIND: &'static str = "Flock";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    /// C++'s watchdog (2 s, reopen and reset), and a pause with advice after every fourth
    /// failure in a row, so that a dead Flock is not hammered with resets.
    fn supervision(&self) -> Supervision {
        Supervision {
            pause: Some(Pause {
                every: FAILURES_BEFORE_PAUSE,
                wait: RETRY_PAUSE,
                advice: ADVICE,
            }),
            ..Supervision::TRACKER
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.framer.clear();
        self.reset.start(cx.now, cx.port());
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        // Bytes after the answer that ends the reset were sent before `'@'`: dropped.
        let p = self.reset.received(bytes, cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.poll(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            if let Some(framed) = self.framer.push(b, cx.now) {
                self.record(framed, cx);
            }
        }
    }

    /// C++'s two texts, the second the one every failure sends.
    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        let (cur, ts) = (cx.now.wall, last_record.wall);
        cx.say(
            TextSeverity::Error,
            format_args!(
                "Tracker failed to read... current_time={}:{}, timestamp={}:{}",
                cur.sec, cur.usec, ts.sec, ts.usec
            ),
        );
        cx.say(TextSeverity::Error, format_args!("{TRYING_TO_RESET}"));
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
    }
}
