//! BG Systems CerealBox on a serial line: a sans-IO [`SerialDriver`] and a device simulator
//! (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_CerealBox NAME PORT BAUD BUTTONS ANALOGS ENCODERS
//! ```
//!
//! Up to 24 buttons, 8 analogs (sliders) and 8 encoders (dials). The box detects the baud
//! rate (19200 is usual). It must carry EEPROM version 3.07.
//!
//! # What is sent
//!
//! `NAME` is an Analog with `ANALOGS` channels, a Button with `BUTTONS` buttons and a Dial
//! with `ENCODERS` dials, as in C++ VRPN. After each record, in this order, all stamped with
//! the arrival of the record's first byte:
//!
//! * a `vrpn_Analog Channel` message (LOW_LATENCY) if any channel changed: each analog's
//!   twelve bits mapped linearly onto -1 to 1;
//! * one `vrpn_Button Change` message (RELIABLE) per changed button (button toggle modes a
//!   client asks for are recorded but, as in C++, not applied);
//! * one `vrpn_Dial update` message (RELIABLE) per encoder that moved: the revolutions
//!   turned since the previous record (4096 ticks a revolution).
//!
//! C++ stamps the analog message with the time it is sent instead.
//!
//! # Supervision
//!
//! Opening the port starts the reset ([`reset`]), which ends by asking for a record. The box
//! is polled: each good record is answered at once with the request for the next (`pE`).
//! Records are found byte by byte ([`framer`]); dropped bytes are reported in a warning text
//! at most once per [`NOTE_INTERVAL`]. A request that gets no record within the record's
//! transmission time plus [`REPOLL_MARGIN`] (a record lost to noise) is repeated, and
//! [`WATCHDOG`] without a good record sends an error text and resets the box.
//!
//! # Differences from C++ VRPN
//!
//! * The reset waits for answers instead of for fixed times, so the first record comes a
//!   few milliseconds after the port opens, not after up to 4 s, and it never blocks the
//!   server. Bytes before the banner are skipped.
//! * C++ stops polling after a damaged record and only recovers through the 2 s watchdog's
//!   reset; here the request is repeated, so one damaged record costs one record.
//! * Records are checked for data characters, not only for the `p` and the LF.
//! * A reset reports the zeroed channels and released buttons (C++ zeroes them silently).
//! * Reset problems and the box type are announced by text messages instead of lines on the
//!   server's standard output and error.

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
use self::record::{revolutions, Layout, REQUEST};
use self::reset::{Failure, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::registry::Driver;
use crate::driver::text::{with_text, Shown};
use crate::serial::{PortKind, PortOps, PortSettings, SerialDriver};
use crate::time::{Now, TimeVal};
use crate::{AnalogServer, ButtonServer, Connection, DialServer, Error};

pub use self::config::CerealBox;

/// The registry entry: `vrpn_CerealBox`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_CerealBox"],
    parse: config::parse,
    hints: &[],
};

/// Longest time without a good record before the box is reset (as C++).
pub const WATCHDOG: Duration = Duration::from_secs(2);
/// Time a polled record may take beyond its transmission before the request is repeated.
pub const REPOLL_MARGIN: Duration = Duration::from_millis(100);
/// At most one note about dropped bytes per this interval.
pub const NOTE_INTERVAL: Duration = Duration::from_secs(1);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Closed,
    Resetting,
    Streaming,
}

/// A CerealBox on one serial port.
pub struct CerealBoxDriver {
    name: String,
    port: String,
    baud: u32,
    layout: Layout,
    analog: AnalogServer,
    buttons: ButtonServer,
    dials: DialServer,
    framer: Framer,
    reset: ResetSequence,
    mode: Mode,
    /// First byte of the last good record, or the end of the reset: the watchdog's start.
    last_record: Option<Now>,
    poll_deadline: Option<Instant>,
    poll_timeout: Duration,
    box_type: Option<u8>,
    records: u64,
    repolls: u64,
    resets: u64,
    unreported: Option<Skipped>,
    last_note: Option<Instant>,
}

impl CerealBoxDriver {
    /// The driver for a `vrpn_CerealBox` entry, with its Analog, Button and Dial served on
    /// `conn`.
    pub fn new(cfg: &CerealBox, conn: &Connection) -> Result<CerealBoxDriver, Error> {
        if cfg.buttons > config::CerealBox::MAX_BUTTONS
            || cfg.analogs > config::CerealBox::MAX_ANALOGS
            || cfg.encoders > config::CerealBox::MAX_ENCODERS
        {
            return Err(Error::Unsupported(
                "a CerealBox has at most 24 buttons, 8 analogs and 8 encoders",
            ));
        }
        let layout = Layout {
            buttons: cfg.buttons as usize,
            analogs: cfg.analogs as usize,
            encoders: cfg.encoders as usize,
        };
        let bits = 10 * (layout.record_len() + REQUEST.len()) as u64 * 1_000_000;
        let transmission = Duration::from_micros(bits.div_ceil(u64::from(cfg.baud.max(1))));
        Ok(CerealBoxDriver {
            name: cfg.name.clone(),
            port: cfg.port.clone(),
            baud: cfg.baud,
            layout,
            analog: AnalogServer::new(&cfg.name, conn, layout.analogs)?,
            buttons: ButtonServer::new(&cfg.name, conn, layout.buttons)?,
            dials: DialServer::new(&cfg.name, conn, layout.encoders)?,
            framer: Framer::new(&layout),
            reset: ResetSequence::new(&layout),
            mode: Mode::Closed,
            last_record: None,
            poll_deadline: None,
            poll_timeout: transmission + REPOLL_MARGIN,
            box_type: None,
            records: 0,
            repolls: 0,
            resets: 0,
            unreported: None,
            last_note: None,
        })
    }

    /// The serial port to open, as the configuration gives it.
    pub fn port(&self) -> &str {
        &self.port
    }

    /// Which inputs are read.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The analog server.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// The dial server.
    pub fn dials(&self) -> &DialServer {
        &self.dials
    }

    /// True once a reset succeeded and the box is polled.
    pub fn is_streaming(&self) -> bool {
        self.mode == Mode::Streaming
    }

    /// The box type letter from the last banner.
    pub fn box_type(&self) -> Option<u8> {
        self.box_type
    }

    /// Good records reported since construction.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Requests repeated because no record came.
    pub fn repolls(&self) -> u64 {
        self.repolls
    }

    /// Resets begun since construction (the first one included).
    pub fn resets(&self) -> u64 {
        self.resets
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

    fn begin_reset(&mut self, now: Now, port: &mut PortOps) {
        self.mode = Mode::Resetting;
        self.resets += 1;
        self.framer.clear();
        self.last_record = None;
        self.poll_deadline = None;
        self.unreported = None;
        self.analog.channels_mut().fill(0.0);
        for i in 0..self.layout.buttons {
            self.buttons.set_button(i, false);
        }
        let _ = self.analog.report_changes(Some(now.wall));
        self.buttons.set_timestamp(now.wall);
        let _ = self.buttons.report_changes_unfiltered();
        self.reset.start(now, port);
    }

    fn progress(&mut self, p: Progress, now: Now) {
        let sev = TextSeverity::Warning;
        match p {
            Progress::Busy => {}
            Progress::Found(t) => {
                self.box_type = Some(t);
                self.say(
                    TextSeverity::Normal,
                    format_args!("vrpn_CerealBox: Box of type {} found", Shown(t)),
                );
            }
            Progress::Done => {
                self.mode = Mode::Streaming;
                self.last_record = Some(now);
                self.poll_deadline = Some(now.mono + self.poll_timeout);
            }
            Progress::Failed(f) => match f {
                Failure::NoBanner => {
                    self.say(sev, format_args!("vrpn_CerealBox: No response from box"))
                }
                Failure::ShortBanner(n) => self.say(
                    sev,
                    format_args!("vrpn_CerealBox: Got {n} of 44 expected characters"),
                ),
                Failure::BadVersion([a, b, c]) => self.say(
                    sev,
                    format_args!(
                        "vrpn_CerealBox: Bad EEPROM version (want 3.07, got {}.{}{})",
                        a as char, b as char, c as char
                    ),
                ),
                Failure::NoAck => self.say(sev, format_args!("vrpn_CerealBox: No ack from box")),
                Failure::ShortAck => self.say(
                    sev,
                    format_args!("vrpn_CerealBox: Got 1 of 2 expected ack characters"),
                ),
                Failure::BadAck(b) => self.say(
                    sev,
                    format_args!("vrpn_CerealBox: Bad ack: wanted 'a', got {}", Shown(b)),
                ),
            },
        }
    }

    fn stream(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        for &b in bytes {
            if let Some(framed) = self.framer.push(b, arrived) {
                self.report(&framed, arrived, port);
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
            Problem::NotRecordStart(b) => ("looking for 'p'", b),
            Problem::BadCharacter(b) => ("a bad character in a record", b),
            Problem::NoLineFeed(b) => ("no line feed at the end of a record", b),
        };
        self.say(
            TextSeverity::Warning,
            format_args!(
                "vrpn_CerealBox: skipped {} bytes to resynchronise (first: {what}, got {})",
                u.bytes,
                Shown(b)
            ),
        );
    }

    /// Asks for the next record, then decodes and reports this one.
    fn report(&mut self, framed: &Framed, arrived: Now, port: &mut PortOps) {
        port.write(REQUEST);
        self.poll_deadline = Some(arrived.mono + self.poll_timeout);
        let at = framed.first_byte;
        self.note_skipped(framed.skipped, at);
        self.last_record = Some(at);
        self.records += 1;
        let rec = framed.bytes();
        let l = self.layout;
        for i in 0..l.analogs {
            self.analog.set_channel(i, l.analog_of(rec, i));
        }
        let mask = l.buttons_of(rec);
        for i in 0..l.buttons {
            self.buttons.set_button(i, mask & (1 << i) != 0);
        }
        for i in 0..l.encoders {
            self.dials.set_dial(i, revolutions(l.encoder_of(rec, i)));
        }
        self.send_reports(at.wall);
    }

    fn send_reports(&mut self, time: TimeVal) {
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.analog.report_changes(Some(time));
        self.buttons.set_timestamp(time);
        let _ = self.buttons.report_changes_unfiltered();
        self.dials.set_timestamp(time);
        let _ = self.dials.report_changes();
    }

    fn supervise(&mut self, now: Now, port: &mut PortOps) {
        if self
            .last_record
            .is_some_and(|t| now.mono >= t.mono + WATCHDOG)
        {
            self.say(
                TextSeverity::Error,
                format_args!("Too long since last report, resetting"),
            );
            self.begin_reset(now, port);
            return;
        }
        if self.poll_deadline.is_some_and(|t| now.mono >= t) {
            port.write(REQUEST);
            self.repolls += 1;
            self.poll_deadline = Some(now.mono + self.poll_timeout);
        }
    }
}

impl SerialDriver for CerealBoxDriver {
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
            Mode::Closed => {}
            Mode::Resetting => {
                let (p, used) = self.reset.received(bytes, arrived, port);
                self.progress(p, arrived);
                if self.mode == Mode::Streaming {
                    self.stream(&bytes[used..], arrived, port);
                }
            }
            Mode::Streaming => self.stream(bytes, arrived, port),
        }
    }

    fn poll(&mut self, now: Now, port: &mut PortOps) {
        match self.mode {
            Mode::Closed => {}
            Mode::Resetting => {
                let p = self.reset.poll(now, port);
                self.progress(p, now);
            }
            Mode::Streaming => self.supervise(now, port),
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        match self.mode {
            Mode::Closed => None,
            Mode::Resetting => self.reset.deadline(),
            Mode::Streaming => {
                let watchdog = self.last_record.map(|t| t.mono + WATCHDOG);
                watchdog.into_iter().chain(self.poll_deadline).min()
            }
        }
    }

    fn closed(&mut self, _now: Now) {
        self.mode = Mode::Closed;
        self.reset.stop();
        self.framer.clear();
        self.last_record = None;
        self.poll_deadline = None;
    }
}
