//! BG Systems CerealBox on a serial line: its `vrpn.cfg` line ([`config`]), its [`Protocol`] run
//! by the shared [`Lifecycle`](crate::driver::Lifecycle), and a device simulator (`sim`, with
//! the `sim` feature).
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
//! at most once a second. A request that gets no record within the record's
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
//! * A reset reports nothing by itself: the values a client holds stay as the box last sent
//!   them until its first record after the reset (C++ zeroes them silently; reporting zeros
//!   would show values the box never sent, and held buttons would bounce).
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

use self::framer::{Format, Framed, Framer, Problem};
use self::record::{revolutions, Layout, REQUEST};
use self::reset::{Failure, Progress, ResetSequence, RETRY_PAUSE};
use crate::devices::text::TextSeverity;
use crate::driver::text::Shown;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::TimeVal;
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

/// The CerealBox's protocol. See the module documentation.
pub struct CerealBoxProtocol {
    port: String,
    baud: u32,
    layout: Layout,
    analog: AnalogServer,
    buttons: ButtonServer,
    dials: DialServer,
    framer: Framer,
    reset: ResetSequence,
    poll_deadline: Option<Instant>,
    poll_timeout: Duration,
    box_type: Option<u8>,
    repolls: u64,
}

impl CerealBoxProtocol {
    /// The protocol of a `vrpn_CerealBox` entry, with its Analog, Button and Dial served on
    /// `conn`.
    pub fn new(cfg: &CerealBox, conn: &Connection) -> Result<CerealBoxProtocol, Error> {
        if cfg.buttons > CerealBox::MAX_BUTTONS
            || cfg.analogs > CerealBox::MAX_ANALOGS
            || cfg.encoders > CerealBox::MAX_ENCODERS
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
        Ok(CerealBoxProtocol {
            port: cfg.port.clone(),
            baud: cfg.baud,
            layout,
            analog: AnalogServer::new(&cfg.name, conn, layout.analogs)?,
            buttons: ButtonServer::new(&cfg.name, conn, layout.buttons)?,
            dials: DialServer::new(&cfg.name, conn, layout.encoders)?,
            framer: Framer::new(Format::new(&layout)),
            reset: ResetSequence::new(&layout),
            poll_deadline: None,
            poll_timeout: transmission + REPOLL_MARGIN,
            box_type: None,
            repolls: 0,
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

    /// The box type letter from the last banner.
    pub fn box_type(&self) -> Option<u8> {
        self.box_type
    }

    /// Requests repeated because no record came.
    pub fn repolls(&self) -> u64 {
        self.repolls
    }

    /// Bytes dropped while looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        let sev = TextSeverity::Warning;
        match p {
            Progress::Busy => Reset::Working,
            Progress::Found(t) => {
                self.box_type = Some(t);
                cx.say(
                    TextSeverity::Normal,
                    format_args!("vrpn_CerealBox: Box of type {} found", Shown(t)),
                );
                Reset::Working
            }
            Progress::Done => {
                self.poll_deadline = Some(cx.now.mono + self.poll_timeout);
                Reset::Done
            }
            Progress::Failed(f) => {
                match f {
                    Failure::NoBanner => {
                        cx.say(sev, format_args!("vrpn_CerealBox: No response from box"))
                    }
                    Failure::ShortBanner(n) => cx.say(
                        sev,
                        format_args!("vrpn_CerealBox: Got {n} of 44 expected characters"),
                    ),
                    Failure::BadVersion([a, b, c]) => cx.say(
                        sev,
                        format_args!(
                            "vrpn_CerealBox: Bad EEPROM version (want 3.07, got {}.{}{})",
                            a as char, b as char, c as char
                        ),
                    ),
                    Failure::NoAck => cx.say(sev, format_args!("vrpn_CerealBox: No ack from box")),
                    Failure::ShortAck => cx.say(
                        sev,
                        format_args!("vrpn_CerealBox: Got 1 of 2 expected ack characters"),
                    ),
                    Failure::BadAck(b) => cx.say(
                        sev,
                        format_args!("vrpn_CerealBox: Bad ack: wanted 'a', got {}", Shown(b)),
                    ),
                }
                Reset::Failed(Retry::After(RETRY_PAUSE))
            }
        }
    }

    fn stream(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            if let Some(framed) = self.framer.push(b, cx.now) {
                self.report(&framed, cx);
            }
        }
    }

    /// Asks for the next record, then decodes and reports this one.
    fn report(&mut self, framed: &Framed, cx: &mut Cx<'_>) {
        cx.write(REQUEST);
        self.poll_deadline = Some(cx.now.mono + self.poll_timeout);
        let at = framed.first_byte;
        if let Some(s) = framed.skipped {
            let (what, b) = match s.first {
                Problem::NotRecordStart(b) => ("looking for 'p'", b),
                Problem::BadCharacter(b) => ("a bad character in a record", b),
                Problem::BadLastByte(b) => ("no line feed at the end of a record", b),
            };
            cx.skipped(
                s.bytes,
                Self::KIND,
                format_args!(" (first: {what}, got {})", Shown(b)),
            );
        }
        cx.record(at);
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
}

impl Protocol for CerealBoxProtocol {
    const KIND: &'static str = "vrpn_CerealBox";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    /// 2 s without a good record resets the box on the open port (as C++).
    fn supervision(&self) -> Supervision {
        Supervision {
            watchdog: Some(WATCHDOG),
            on_silence: Recovery::Reset,
            ..Supervision::TRACKER
        }
    }

    /// Asks for the banner. Nothing is reported: the values stay as the box last sent them
    /// until its first record after the reset.
    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.poll_deadline = None;
        self.reset.start(cx.now, cx.port());
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let (p, used) = self.reset.received(bytes, cx.now, cx.port());
        let r = self.progress(p, cx);
        if r == Reset::Done {
            // The first record may follow the acknowledgement in the same read. (Bytes after
            // the banner came before the configuration command went out: not its answer.)
            self.stream(&bytes[used..], cx);
        }
        r
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.poll(cx.now);
        self.progress(p, cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.stream(bytes, cx);
    }

    /// A request that got no record in time (a record lost to noise) is repeated.
    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.poll_deadline.is_some_and(|t| cx.now.mono >= t) {
            cx.write(REQUEST);
            self.repolls += 1;
            self.poll_deadline = Some(cx.now.mono + self.poll_timeout);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.poll_deadline
    }

    /// The box's silence text (C++'s), instead of the trackers'.
    fn silent(&mut self, _last_record: crate::time::Now, cx: &mut Cx<'_>) {
        cx.say(
            TextSeverity::Error,
            format_args!("Too long since last report, resetting"),
        );
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
        self.poll_deadline = None;
    }
}
