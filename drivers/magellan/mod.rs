//! Logitech / 3Dconnexion Magellan (SpaceMouse) on a serial line: its `vrpn.cfg` line
//! ([`config`]), its [`Protocol`] run by the shared [`Lifecycle`](crate::driver::Lifecycle),
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
//! in a warning text at most once a second. A mode record that says the device
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
//! * A reset invents nothing: keys keep the state the device last sent until its next key
//!   record, and the axes read 0 once the device answers the zeroing command (`z`), as it
//!   then says (C++ zeroes both silently, so a client keeps stale values).
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

use self::framer::{Format, Framer, Problem, Record};
use self::record::{axis_raw, axis_value, keys, nibble, AXES, BUTTONS, MOUSE_MODE};
use self::reset::{Failure, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::text::{Shown, ShownBytes};
use crate::driver::{Cx, Driver, Protocol, Reset, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::TimeVal;
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

/// The Magellan's protocol. See the module documentation.
pub struct MagellanProtocol {
    port: String,
    baud: u32,
    analog: AnalogServer,
    buttons: ButtonServer,
    framer: Framer,
    reset: ResetSequence,
    null_radius: i32,
    /// First byte of the last record, or the end of the reset: the probe's start.
    last_record: Option<Instant>,
    probe_deadline: Option<Instant>,
    probes: u64,
    resets: u64,
}

impl MagellanProtocol {
    /// The protocol of a `vrpn_Magellan` entry, with its Analog and Button served on `conn`.
    pub fn new(cfg: &Magellan, conn: &Connection) -> Result<MagellanProtocol, Error> {
        let plan = if cfg.alt_reset {
            reset::ALTERNATIVE
        } else {
            reset::NORMAL
        };
        Ok(MagellanProtocol {
            port: cfg.port.clone(),
            baud: cfg.baud,
            analog: AnalogServer::new(&cfg.name, conn, AXES)?,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            framer: Framer::new(Format),
            reset: ResetSequence::new(plan),
            null_radius: record::RESET_NULL_RADIUS,
            last_record: None,
            probe_deadline: None,
            probes: 0,
            resets: 0,
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

    /// The null radius in force.
    pub fn null_radius(&self) -> i32 {
        self.null_radius
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

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Busy => Reset::Working,
            Progress::Done => {
                self.null_radius = record::RESET_NULL_RADIUS;
                self.last_record = Some(cx.now.mono);
                Reset::Done
            }
            Progress::Failed(f) => {
                let sev = TextSeverity::Warning;
                match f {
                    Failure::NoResponse => cx.say(
                        sev,
                        format_args!("vrpn_Magellan reset: No response from device"),
                    ),
                    Failure::TooFew { got, want } => cx.say(
                        sev,
                        format_args!(
                            "vrpn_Magellan reset: Got {got} of {want} expected answers, retrying"
                        ),
                    ),
                    Failure::WrongAnswer { index, got } => cx.say(
                        sev,
                        format_args!(
                            "vrpn_Magellan reset: Bad reset string (expected {}, got {}), retrying",
                            ShownBytes(self.reset.plan().answers[index]),
                            ShownBytes(got.bytes())
                        ),
                    ),
                }
                // The sequence pauses and starts the next attempt itself, so that axis and
                // key records keep being reported meanwhile.
                Reset::Working
            }
        }
    }

    /// Decodes and reports one record; false when it asked for a reset.
    fn report(&mut self, rec: &Record, cx: &mut Cx<'_>) -> bool {
        let at = rec.first_byte;
        if let Some(s) = rec.skipped {
            let (what, b) = match s.first {
                Problem::NotRecordStart(b) => ("a byte that starts no record", b),
                Problem::BadCharacter(b) => ("a bad character in a record", b),
                Problem::BadLastByte(b) => ("no carriage return at the end of a record", b),
            };
            cx.skipped(
                s.bytes,
                Self::KIND,
                format_args!(" (first: {what}, {})", Shown(b)),
            );
        }
        cx.record(at);
        self.last_record = Some(at.mono);
        self.probe_deadline = None;
        let bytes = rec.bytes();
        match rec.start() {
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
                cx.say(
                    TextSeverity::Error,
                    format_args!("vrpn_Magellan: Was put into mouse mode, resetting"),
                );
                cx.reset();
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

    /// Streams `bytes`; stops at a record that asked for a reset (the rest of the read came
    /// before the reset's flush).
    fn stream(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            if let Some(rec) = self.framer.push(b, cx.now) {
                if !self.report(&rec, cx) {
                    return;
                }
            }
        }
    }
}

impl Protocol for MagellanProtocol {
    const KIND: &'static str = "vrpn_Magellan";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    /// The device sends only when something changes: no watchdog, the idle probe instead.
    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.resets += 1;
        self.last_record = None;
        self.probe_deadline = None;
        cx.flush_input();
        self.reset.start(cx.now, cx.port());
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.reset.saw_bytes();
        let mut outcome = Reset::Working;
        for (i, &b) in bytes.iter().enumerate() {
            let Some(rec) = self.framer.push(b, cx.now) else {
                continue;
            };
            if matches!(rec.start(), b'd' | b'k') {
                // Axis and key records during a reset are fresh (the input was flushed).
                if !self.report(&rec, cx) {
                    return Reset::Working;
                }
                continue;
            }
            let p = self.reset.record(&rec, cx.now);
            if rec.bytes() == reset::ZERO_ANSWER && !matches!(p, Progress::Failed(_)) {
                // The device confirms it zeroed the puck: its axes read 0 from now on, as
                // it says (keys are its own business: a held key stays held).
                self.analog.channels_mut().fill(0.0);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.analog.report_changes(Some(rec.first_byte.wall));
            }
            outcome = self.progress(p, cx);
            if outcome == Reset::Done {
                self.stream(&bytes[i + 1..], cx);
                return Reset::Done;
            }
        }
        outcome
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.poll(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.stream(bytes, cx);
    }

    /// The idle probe: after [`IDLE_PROBE`] without a record, ask for the mode; no answer
    /// within [`PROBE_TIMEOUT`] resets the device.
    fn poll(&mut self, cx: &mut Cx<'_>) {
        if let Some(deadline) = self.probe_deadline {
            if cx.now.mono >= deadline {
                cx.say(
                    TextSeverity::Error,
                    format_args!("vrpn_Magellan: No answer to a mode query, resetting"),
                );
                cx.reset();
            }
            return;
        }
        if self
            .last_record
            .is_some_and(|t| cx.now.mono >= t + IDLE_PROBE)
        {
            cx.write(PROBE);
            self.probes += 1;
            self.probe_deadline = Some(cx.now.mono + PROBE_TIMEOUT);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.probe_deadline
            .or_else(|| self.last_record.map(|t| t + IDLE_PROBE))
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
        self.probe_deadline = None;
    }
}
