//! Origin Instruments DynaSight (and the SeeReal D4D head tracker that speaks its protocol):
//! a sans-IO [`SerialDriver`] and a device simulator ([`sim`]).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_Dyna NAME SENSORS PORT BAUD
//! ```
//!
//! Note the sensor count before the port. The tracker `NAME` has `SENSORS` sensors, but the
//! DynaSight tracks one target and only sensor 0 is ever reported (as C++). The line is 8N1
//! at `BAUD`, without flow control.
//!
//! # What is sent
//!
//! One `vrpn_Tracker Pos_Quat` message (LOW_LATENCY) per record: sensor 0, position in
//! metres ([`record`]), orientation the identity, stamped with the time the record's first
//! byte arrived. Resets, time-outs and resynchronisations are announced as text messages
//! from `NAME`.
//!
//! # Supervision
//!
//! Opening the port starts the reset ([`reset`]), a state machine over deadlines. An attempt
//! that gets no answer starts again at once (it already waited 2 s); one that gets a wrong
//! answer starts again after [`RETRY_DELAY`]. Records are found byte by byte ([`framing`]),
//! so garbage costs no record after it. More than [`WATCHDOG`] without a record (counted
//! from the end of the reset, then from each record's first byte) sends two error texts, and
//! the port is reopened and the DynaSight reset.
//!
//! # Differences from C++ VRPN
//!
//! * The reset waits for the device instead of sleeping 1 + 2 + 1 s: about 0.1 s on a
//!   DynaSight that answers at once, and it never blocks other devices.
//! * The watchdog starts when the reset ends. (C++ sets the watchdog's start to a time
//!   of −1 s, so whether its first check fires depends on a 32-bit overflow.)
//! * A failed candidate record gives up one byte, not eight: the record after it is kept.
//! * Problems go to clients as text messages, not to the server's standard error.

pub mod framing;
pub mod record;
pub mod reset;
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::framing::{Framed, Framer};
use self::record::IDENTITY_XYZW;
use self::reset::{Failure, Progress, ResetSequence, STATUS_LEN};
use super::stack_text::with_text;
use crate::devices::text::TextSeverity;
use crate::serial::{PortKind, PortOps, PortSettings, SerialDriver};
use crate::server::config;
use crate::time::Now;
use crate::{Connection, Error, TrackerServer};

/// Longest gap without a record before the DynaSight is declared failed and reset (as C++).
pub const WATCHDOG: Duration = Duration::from_secs(2);
/// Pause before another attempt after a wrong status answer.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);
/// At most one "skipped bytes" note per this interval.
pub const SKIP_NOTE_INTERVAL: Duration = Duration::from_secs(1);

/// Where the driver is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// The port is closed (or being reopened).
    Closed,
    /// A reset attempt runs.
    Resetting,
    /// Waiting before the next reset attempt.
    Retrying { at: Instant },
    /// Records are streaming.
    Streaming,
}

/// An Origin Instruments DynaSight on one serial port.
pub struct DynaDriver {
    name: String,
    port: String,
    baud: u32,
    tracker: TrackerServer,
    reset: ResetSequence,
    framer: Framer,
    mode: Mode,
    /// First byte of the last record, or the end of the reset: the watchdog's start.
    last_record: Option<Now>,
    records: u64,
    resets: u64,
    unreported_skips: u64,
    last_skip_note: Option<Instant>,
}

impl DynaDriver {
    /// The driver for a `vrpn_Tracker_Dyna` entry, with its tracker served on `conn`.
    pub fn new(cfg: &config::Dyna, conn: &Connection) -> Result<DynaDriver, Error> {
        if cfg.sensors == 0 {
            return Err(Error::Unsupported("a DynaSight needs at least one sensor"));
        }
        let tracker = TrackerServer::new(&cfg.name, conn, cfg.sensors as usize)?;
        Ok(DynaDriver {
            name: cfg.name.clone(),
            port: cfg.port.clone(),
            baud: cfg.baud,
            tracker,
            reset: ResetSequence::new(),
            framer: Framer::new(),
            mode: Mode::Closed,
            last_record: None,
            records: 0,
            resets: 0,
            unreported_skips: 0,
            last_skip_note: None,
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

    /// True once a reset finished and records are expected.
    pub fn is_streaming(&self) -> bool {
        self.mode == Mode::Streaming
    }

    /// Records reported since construction.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Resets completed since construction.
    pub fn resets(&self) -> u64 {
        self.resets
    }

    /// Reset attempts since the last completed one.
    pub fn reset_attempts(&self) -> u32 {
        self.reset.attempts()
    }

    /// Bytes skipped while looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn say(&self, severity: TextSeverity, args: std::fmt::Arguments<'_>) {
        // A failed send is the connection's business (it reports and drops the peer).
        with_text(args, |text| {
            let _ = self.tracker.send_text(severity, 0, text);
        });
    }

    fn progress(&mut self, p: Progress, now: Now) {
        match p {
            Progress::Working => {}
            Progress::Done { kept_sending } => {
                if kept_sending {
                    self.say(
                        TextSeverity::Warning,
                        format_args!(
                            "DynaSight kept sending after the stop command (check the baud rate)"
                        ),
                    );
                }
                self.mode = Mode::Streaming;
                self.framer.clear();
                self.last_record = Some(now);
                self.resets += 1;
                self.say(
                    TextSeverity::Normal,
                    format_args!("DynaSight reset: valid status, continuous output requested"),
                );
            }
            Progress::Failed(f) => {
                let attempt = self.reset.attempts();
                let at = match f {
                    Failure::NoAnswer => {
                        self.say(
                            TextSeverity::Warning,
                            format_args!(
                                "DynaSight reset attempt {attempt}: no data (is the tracker \
                                 turned on?); trying again"
                            ),
                        );
                        now.mono
                    }
                    Failure::Incomplete(n) => {
                        self.say(
                            TextSeverity::Error,
                            format_args!(
                                "DynaSight reset attempt {attempt}: {n} of {STATUS_LEN} bytes \
                                 of the status answer (check the baud rate); trying again"
                            ),
                        );
                        now.mono + RETRY_DELAY
                    }
                    Failure::BadStatus([a, b]) => {
                        self.say(
                            TextSeverity::Error,
                            format_args!(
                                "DynaSight reset attempt {attempt}: the status answer starts \
                                 0x{a:02X} 0x{b:02X}, not a status record (check the baud \
                                 rate); trying again"
                            ),
                        );
                        now.mono + RETRY_DELAY
                    }
                };
                self.mode = Mode::Retrying { at };
            }
        }
    }

    fn record(&mut self, framed: Framed) {
        if framed.skipped > 0 {
            self.note_skips(framed.skipped, framed.first_byte.mono);
        }
        self.last_record = Some(framed.first_byte);
        self.records += 1;
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.tracker.report_pose(
            0,
            framed.first_byte.wall,
            record::position_m(&framed.bytes),
            IDENTITY_XYZW,
        );
    }

    fn note_skips(&mut self, n: u32, now: Instant) {
        self.unreported_skips += u64::from(n);
        if self
            .last_skip_note
            .is_some_and(|t| now < t + SKIP_NOTE_INTERVAL)
        {
            return;
        }
        self.say(
            TextSeverity::Warning,
            format_args!(
                "DynaSight: skipped {} bytes to find the next record",
                self.unreported_skips
            ),
        );
        self.unreported_skips = 0;
        self.last_skip_note = Some(now);
    }

    fn watchdog(&mut self, now: Now, port: &mut PortOps) {
        let Some(last) = self.last_record else {
            return;
        };
        if now.mono < last.mono + WATCHDOG {
            return;
        }
        let (cur, ts) = (now.wall, last.wall);
        self.say(
            TextSeverity::Error,
            format_args!(
                "Tracker failed to read... current_time={}:{}, timestamp={}:{}",
                cur.sec, cur.usec, ts.sec, ts.usec
            ),
        );
        self.say(
            TextSeverity::Error,
            format_args!(
                "Tracker failed, trying to reset (Try power cycle if more than 4 attempts made)"
            ),
        );
        self.mode = Mode::Closed;
        self.last_record = None;
        self.framer.clear();
        port.reopen();
    }

    fn start_reset(&mut self, now: Now, port: &mut PortOps) {
        self.framer.clear();
        self.last_record = None;
        self.mode = Mode::Resetting;
        self.reset.start(now, port);
    }
}

impl SerialDriver for DynaDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn opened(&mut self, now: Now, port: &mut PortOps) {
        self.start_reset(now, port);
    }

    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        match self.mode {
            Mode::Closed | Mode::Retrying { .. } => {}
            Mode::Resetting => {
                // Bytes after a complete status answer are flushed with the rest of the input.
                let p = self.reset.received(bytes, arrived, port);
                self.progress(p, arrived);
            }
            Mode::Streaming => {
                for &b in bytes {
                    if let Some(framed) = self.framer.push(b, arrived) {
                        self.record(framed);
                    }
                }
            }
        }
    }

    fn poll(&mut self, now: Now, port: &mut PortOps) {
        match self.mode {
            Mode::Closed => {}
            Mode::Resetting => {
                let p = self.reset.poll(now, port);
                self.progress(p, now);
            }
            Mode::Retrying { at } => {
                if now.mono >= at {
                    self.start_reset(now, port);
                }
            }
            Mode::Streaming => self.watchdog(now, port),
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        match self.mode {
            Mode::Closed => None,
            Mode::Resetting => self.reset.deadline(),
            Mode::Retrying { at } => Some(at),
            Mode::Streaming => self.last_record.map(|t| t.mono + WATCHDOG),
        }
    }

    fn closed(&mut self, _now: Now) {
        self.mode = Mode::Closed;
        self.reset.stop();
        self.framer.clear();
        self.last_record = None;
    }
}
