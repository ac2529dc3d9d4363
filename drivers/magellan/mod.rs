//! Logitech / 3Dconnexion Magellan (SpaceMouse) on a serial line: a sans-IO [`SerialDriver`]
//! and a device simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Magellan NAME PORT BAUD [altreset]
//! ```
//!
//! `BAUD` is 9600 for the standard device. `altreset` selects the reset commands of older
//! units (see [`reset`]).
//!
//! # What is sent
//!
//! `NAME` is an Analog with six channels and a Button with nine buttons, as in C++ VRPN:
//!
//! * channels 0, 1, 2 are the X, Y, Z translations and 3, 4, 5 the A, B, C rotations of the
//!   puck: the raw value is 0 within the null radius (8 after a reset, or what the device
//!   last announced), else raw / 7500, so about -1 to 1;
//! * button 0 is the `*` key, buttons 1 to 8 the numbered keys.
//!
//! After each record, a `vrpn_Analog Channel` message with all six channels if any changed
//! (LOW_LATENCY), then one `vrpn_Button Change` message per changed button (RELIABLE), both
//! stamped with the arrival of the record's first byte (C++ stamps the analog message with
//! the time it is sent). Button toggle modes a client asks for are recorded but, as in C++,
//! not applied to the reports.
//!
//! # Supervision
//!
//! Opening the port starts the reset ([`reset`]); records are found byte by byte
//! ([`framer`]), so garbage costs at most the record it hits, and dropped bytes are reported
//! in a warning text at most once per [`NOTE_INTERVAL`]. A mode record that says the device
//! was switched to mouse mode sends an error text and resets it.
//!
//! The device sends only when the puck moves or a key changes, so silence is normal. After
//! [`IDLE_PROBE`] without a record the driver asks for the mode (`mQ`), which the device
//! answers with a mode record; no answer within [`PROBE_TIMEOUT`] sends an error text and
//! resets the device, and the reset is retried until it answers again.
//!
//! # Differences from C++ VRPN
//!
//! * No 1 s sleep before the first reset, and the reset ends when the last answer arrives
//!   instead of after a fixed wait; it never blocks the server.
//! * Answers interleaved with axis or key records (the puck was touched during the reset) are
//!   accepted, and those records are reported (C++ loses them).
//! * A byte that starts no record is skipped rather than triggering a full reset, and records
//!   are checked for data characters, not only for the final CR.
//! * The mode query above: C++ has no watchdog and never notices a device that stopped
//!   answering.
//! * A reset reports the zeroed channels and released buttons (C++ zeroes them silently, so a
//!   client keeps the old values).
//! * Resets are announced by warning texts instead of lines on the server's standard error.

pub mod config;
pub mod framer;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::framer::{Framed, Framer, Problem, Skipped};
use self::record::{axis_raw, axis_value, keys, nibble, AXES, BUTTONS, MOUSE_MODE};
use self::reset::{Failure, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::registry::Driver;
use crate::driver::text::{with_text, Shown, ShownBytes};
use crate::serial::{PortKind, PortOps, PortSettings, SerialDriver};
use crate::time::{Now, TimeVal};
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::Magellan;

/// The registry entry: `vrpn_Magellan`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Magellan"],
    parse: config::parse,
    hints: &[],
};

/// Silence after which the device is asked for its mode, to prove it is still there.
pub const IDLE_PROBE: Duration = Duration::from_secs(2);
/// Time the device has to answer that query.
pub const PROBE_TIMEOUT: Duration = Duration::from_secs(1);
/// The query: "which mode are you in?", answered by a mode record.
pub const PROBE: &[u8] = b"mQ\r";
/// At most one note about dropped bytes per this interval.
pub const NOTE_INTERVAL: Duration = Duration::from_secs(1);

/// Where the driver is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Closed,
    Resetting,
    Streaming,
}

/// A Magellan on one serial port.
pub struct MagellanDriver {
    name: String,
    port: String,
    baud: u32,
    analog: AnalogServer,
    buttons: ButtonServer,
    framer: Framer,
    reset: ResetSequence,
    mode: Mode,
    null_radius: i32,
    /// First byte of the last record, or the end of the reset: the probe's start.
    last_record: Option<Now>,
    probe_deadline: Option<Instant>,
    probes: u64,
    records: u64,
    resets: u64,
    unreported: Option<Skipped>,
    last_note: Option<Instant>,
}

impl MagellanDriver {
    /// The driver for a `vrpn_Magellan` entry, with its Analog and Button served on `conn`.
    pub fn new(cfg: &Magellan, conn: &Connection) -> Result<MagellanDriver, Error> {
        let plan = if cfg.alt_reset {
            reset::ALTERNATIVE
        } else {
            reset::NORMAL
        };
        Ok(MagellanDriver {
            name: cfg.name.clone(),
            port: cfg.port.clone(),
            baud: cfg.baud,
            analog: AnalogServer::new(&cfg.name, conn, AXES)?,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            framer: Framer::new(),
            reset: ResetSequence::new(plan),
            mode: Mode::Closed,
            null_radius: record::RESET_NULL_RADIUS,
            last_record: None,
            probe_deadline: None,
            probes: 0,
            records: 0,
            resets: 0,
            unreported: None,
            last_note: None,
        })
    }

    /// The serial port to open, as the configuration gives it.
    pub fn port(&self) -> &str {
        &self.port
    }

    /// The analog server (six channels).
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The button server (nine buttons).
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// True once a reset succeeded and records are decoded.
    pub fn is_streaming(&self) -> bool {
        self.mode == Mode::Streaming
    }

    /// The null radius in force.
    pub fn null_radius(&self) -> i32 {
        self.null_radius
    }

    /// Good records decoded since construction (reset answers excluded).
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Resets begun since construction (the first one included).
    pub fn resets(&self) -> u64 {
        self.resets
    }

    /// Mode queries sent to an idle device.
    pub fn probes(&self) -> u64 {
        self.probes
    }

    /// Bytes dropped while looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn say(&self, severity: TextSeverity, args: std::fmt::Arguments<'_>) {
        // A failed send is the connection's business (it reports and drops the peer).
        with_text(args, |t| {
            let _ = self.analog.send_text(severity, 0, t);
        });
    }

    /// Zeroes the values (reporting what changed) and starts the reset.
    fn begin_reset(&mut self, now: Now, port: &mut PortOps) {
        self.mode = Mode::Resetting;
        self.resets += 1;
        self.framer.clear();
        self.last_record = None;
        self.probe_deadline = None;
        self.unreported = None;
        self.analog.channels_mut().fill(0.0);
        for i in 0..BUTTONS {
            self.buttons.set_button(i, false);
        }
        self.send_reports(now.wall);
        port.flush_input();
        self.reset.start(now, port);
    }

    fn progress(&mut self, p: Progress, now: Now) {
        match p {
            Progress::Busy => {}
            Progress::Done => {
                self.mode = Mode::Streaming;
                self.null_radius = record::RESET_NULL_RADIUS;
                self.last_record = Some(now);
            }
            Progress::Failed(f) => {
                let sev = TextSeverity::Warning;
                match f {
                    Failure::NoResponse => self.say(
                        sev,
                        format_args!("vrpn_Magellan reset: No response from device"),
                    ),
                    Failure::TooFew { got, want } => self.say(
                        sev,
                        format_args!(
                            "vrpn_Magellan reset: Got {got} of {want} expected answers, retrying"
                        ),
                    ),
                    Failure::WrongAnswer { index, got } => self.say(
                        sev,
                        format_args!(
                            "vrpn_Magellan reset: Bad reset string (expected {}, got {}), retrying",
                            ShownBytes(self.reset.plan().answers[index]),
                            ShownBytes(got.bytes())
                        ),
                    ),
                }
            }
        }
    }

    fn note_skipped(&mut self, skipped: Option<Skipped>, at: Now) {
        if let Some(s) = skipped {
            match &mut self.unreported {
                Some(u) => u.bytes += s.bytes,
                None => self.unreported = Some(s),
            }
        }
        let Some(u) = self.unreported else { return };
        if self.last_note.is_some_and(|t| at.mono < t + NOTE_INTERVAL) {
            return;
        }
        self.last_note = Some(at.mono);
        self.unreported = None;
        let (what, b) = match u.first {
            Problem::NotRecordStart(b) => ("a byte that starts no record", b),
            Problem::BadCharacter(b) => ("a bad character in a record", b),
            Problem::NoCarriageReturn(b) => ("no carriage return at the end of a record", b),
        };
        self.say(
            TextSeverity::Warning,
            format_args!(
                "vrpn_Magellan: skipped {} bytes to resynchronise (first: {what}, {})",
                u.bytes,
                Shown(b)
            ),
        );
    }

    /// Decodes and reports one record; false when it started a reset.
    fn report(&mut self, framed: Framed, port: &mut PortOps) -> bool {
        let rec = framed.record;
        let at = rec.first_byte;
        self.note_skipped(framed.skipped, at);
        self.last_record = Some(at);
        self.probe_deadline = None;
        self.records += 1;
        let bytes = rec.bytes();
        match rec.letter() {
            b'd' => {
                for i in 0..AXES {
                    let v = axis_value(axis_raw(bytes, i), self.null_radius);
                    self.analog.set_channel(i, v);
                }
            }
            b'k' => {
                let mask = keys(bytes);
                for i in 0..BUTTONS {
                    self.buttons.set_button(i, mask & (1 << i) != 0);
                }
            }
            b'n' => self.null_radius = i32::from(nibble(bytes[1])),
            b'm' if nibble(bytes[1]) & MOUSE_MODE != 0 => {
                self.say(
                    TextSeverity::Error,
                    format_args!("vrpn_Magellan: Was put into mouse mode, resetting"),
                );
                self.begin_reset(at, port);
                return false;
            }
            // Beep, mode, sensitivity, zero, periods and compression answers need nothing.
            _ => {}
        }
        self.send_reports(at.wall);
        true
    }

    fn send_reports(&mut self, time: TimeVal) {
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.analog.report_changes(Some(time));
        self.buttons.set_timestamp(time);
        let _ = self.buttons.report_changes_unfiltered();
    }

    fn watchdog(&mut self, now: Now, port: &mut PortOps) {
        if let Some(deadline) = self.probe_deadline {
            if now.mono >= deadline {
                self.say(
                    TextSeverity::Error,
                    format_args!("vrpn_Magellan: No answer to a mode query, resetting"),
                );
                self.begin_reset(now, port);
            }
            return;
        }
        if self
            .last_record
            .is_some_and(|t| now.mono >= t.mono + IDLE_PROBE)
        {
            port.write(PROBE);
            self.probes += 1;
            self.probe_deadline = Some(now.mono + PROBE_TIMEOUT);
        }
    }
}

impl SerialDriver for MagellanDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn opened(&mut self, now: Now, port: &mut PortOps) {
        self.begin_reset(now, port);
    }

    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        match self.mode {
            Mode::Closed => return,
            Mode::Resetting => self.reset.saw_bytes(),
            Mode::Streaming => {}
        }
        for &b in bytes {
            let Some(framed) = self.framer.push(b, arrived) else {
                continue;
            };
            match self.mode {
                Mode::Closed => return,
                // Axis and key records during a reset are fresh (the input was flushed).
                Mode::Resetting if !matches!(framed.record.letter(), b'd' | b'k') => {
                    let p = self.reset.record(&framed.record, arrived);
                    self.progress(p, arrived);
                }
                Mode::Resetting => {
                    self.report(framed, port);
                }
                Mode::Streaming => {
                    if !self.report(framed, port) {
                        // The rest of this read came before the reset's flush.
                        return;
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
            Mode::Streaming => self.watchdog(now, port),
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        match self.mode {
            Mode::Closed => None,
            Mode::Resetting => self.reset.deadline(),
            Mode::Streaming => self
                .probe_deadline
                .or_else(|| self.last_record.map(|t| t.mono + IDLE_PROBE)),
        }
    }

    fn closed(&mut self, _now: Now) {
        self.mode = Mode::Closed;
        self.reset.stop();
        self.framer.clear();
        self.last_record = None;
        self.probe_deadline = None;
    }
}
