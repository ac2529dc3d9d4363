//! The Immersion Interface Box (buttons, analog inputs and encoders behind a serial line):
//! its `vrpn.cfg` line ([`config`]), its reset ([`reset`]) and records ([`record`]), its
//! [`Protocol`] run by the shared [`Lifecycle`](crate::driver::Lifecycle), and a device
//! simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_ImmersionBox NAME PORT BAUD BUTTONS ANALOGS ENCODERS
//! ```
//!
//! The line is 8N1 at `BAUD` (the box learns the rate from the synchronisation string).
//! At most 7 buttons, 8 analog inputs and 6 encoders: a larger count is an error naming the
//! limit (C++ reduces it and prints a line on its standard error).
//!
//! # What is sent
//!
//! `NAME` is a Button with `BUTTONS` buttons, an Analog with `ANALOGS` channels and a Dial
//! with `ENCODERS` dials, as in C++. Each record (every 10 ms) sends one `vrpn_Button Change`
//! per changed button (bit *i* of the button byte is button *i*), stamped with the arrival of
//! the record's first byte. The analog and encoder bytes are read and discarded, as C++ does:
//! how they encode values is not in the public source, so the Analog and Dial never report.
//!
//! # Reset and supervision
//!
//! The reset ([`reset`]) is C++'s sequence over deadlines: `E`, `IMMC` until echoed, `BEGIN`
//! answered `IBOX`, the seven identification commands (their answers are announced in one
//! normal text), then the configuration, echoed `CF`. A failed attempt sends a warning text
//! and starts again at once (the synchronisation alone may take 10 s). More than 2 s without
//! a record sends C++'s text `Too long since last report, resetting` (error) and resets the
//! box. A port that fails is reopened by the serial layer.
//!
//! # Differences from C++ VRPN
//!
//! * C++ busy-waits 10 ms + 15 ms + 7 × 100 ms + 100 ms (about 0.85 s, the server stalled)
//!   and up to 10 s while the box does not answer; here every step ends at its answer.
//! * A pressed button is sent as 1; C++ sends the button's bit value (2, 4, 8, … for buttons
//!   1, 2, 3, …), which clients comparing with 1 take for released.
//! * With 4 encoders C++ asks for six (configuration bits 0x03) but reads records as if it
//!   had asked for four, losing a third of the stream to resynchronisation; here the record
//!   length follows what was asked for.
//! * Reports carry the arrival of the record's first byte (C++: the time it was decoded).
//! * The identification is announced to clients; the reset's progress and problems are VRPN
//!   text messages, not lines on the server's standard output and error.

pub mod config;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::record::{config_byte, Framer};
use self::reset::{Failure, Progress, ResetSequence, IDENT_COMMANDS, IDENT_NAMES};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, DialServer, Error};

pub use self::config::ImmersionBox;

/// The registry entry: `vrpn_ImmersionBox`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_ImmersionBox"],
    parse: config::parse,
    hints: &[],
};

/// Longest silence before the box is reset (C++'s 2 s).
pub const WATCHDOG: Duration = Duration::from_secs(2);

/// The Immersion box's protocol. See the module documentation.
pub struct ImmersionBoxProtocol {
    baud: u32,
    num_buttons: usize,
    buttons: ButtonServer,
    analog: AnalogServer,
    dials: DialServer,
    reset: ResetSequence,
    framer: Framer,
}

impl ImmersionBoxProtocol {
    /// The protocol of a `vrpn_ImmersionBox` entry, with its servers on `conn`.
    pub fn new(cfg: &ImmersionBox, conn: &Connection) -> Result<ImmersionBoxProtocol, Error> {
        let config = config_byte(cfg.analogs, cfg.encoders);
        Ok(ImmersionBoxProtocol {
            baud: cfg.baud,
            num_buttons: cfg.buttons as usize,
            buttons: ButtonServer::new(&cfg.name, conn, cfg.buttons as usize)?,
            analog: AnalogServer::new(&cfg.name, conn, cfg.analogs as usize)?,
            dials: DialServer::new(&cfg.name, conn, cfg.encoders as usize)?,
            reset: ResetSequence::new(config, cfg.baud),
            framer: Framer::new(config),
        })
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// The analog server (never reports: see the module documentation).
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The dial server (never reports: see the module documentation).
    pub fn dials(&self) -> &DialServer {
        &self.dials
    }

    /// The identification texts of the last reset.
    pub fn ident(&self) -> &[reset::Text; 7] {
        self.reset.ident()
    }

    /// Bytes skipped while looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn progress(&mut self, p: Progress, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Done(from) => {
                let t = self.reset.ident();
                cx.say(
                    TextSeverity::Normal,
                    format_args!(
                        "vrpn_ImmersionBox found: {} {}, {} {}, {} {}, {} {}, {} {}, {} {}, {} {}",
                        IDENT_NAMES[0],
                        ShownBytes(t[0].bytes()),
                        IDENT_NAMES[1],
                        ShownBytes(t[1].bytes()),
                        IDENT_NAMES[2],
                        ShownBytes(t[2].bytes()),
                        IDENT_NAMES[3],
                        ShownBytes(t[3].bytes()),
                        IDENT_NAMES[4],
                        ShownBytes(t[4].bytes()),
                        IDENT_NAMES[5],
                        ShownBytes(t[5].bytes()),
                        IDENT_NAMES[6],
                        ShownBytes(t[6].bytes()),
                    ),
                );
                self.framer.clear();
                self.stream(&bytes[from..], cx);
                Reset::Done
            }
            Progress::Failed(f) => {
                match f {
                    Failure::NoSync => cx.say(
                        TextSeverity::Warning,
                        format_args!(
                            "vrpn_ImmersionBox: no echo of IMMC within 10 s (is the box on?), \
                             retrying"
                        ),
                    ),
                    Failure::NotABox(got, n) => cx.say(
                        TextSeverity::Warning,
                        format_args!(
                            "vrpn_ImmersionBox: BEGIN answered '{}' instead of IBOX, retrying",
                            ShownBytes(&got[..n])
                        ),
                    ),
                    Failure::Ident(i) => cx.say(
                        TextSeverity::Warning,
                        format_args!(
                            "vrpn_ImmersionBox: problems with command 0x{:02X} ({}), retrying",
                            IDENT_COMMANDS[i], IDENT_NAMES[i]
                        ),
                    ),
                    Failure::NoConfigureEcho => cx.say(
                        TextSeverity::Warning,
                        format_args!("vrpn_ImmersionBox: no command echo, retrying"),
                    ),
                }
                Reset::Failed(Retry::Now)
            }
        }
    }

    fn stream(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            if let Some(f) = self.framer.push(b, cx.now) {
                cx.skipped(u64::from(f.skipped), "vrpn_ImmersionBox", format_args!(""));
                cx.record(f.first_byte);
                for i in 0..self.num_buttons {
                    self.buttons.set_button(i, f.buttons & (1 << i) != 0);
                }
                self.buttons.set_timestamp(f.first_byte.wall);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.buttons.report_changes_unfiltered();
            }
        }
    }
}

impl Protocol for ImmersionBoxProtocol {
    const KIND: &'static str = "vrpn_ImmersionBox";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision {
            watchdog: Some(WATCHDOG),
            on_silence: Recovery::Reset,
            ..Supervision::TRACKER
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.reset.start(cx.now, cx.port());
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.received(bytes, cx.now, cx.port());
        self.progress(p, bytes, cx)
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.poll(cx.now, cx.port());
        self.progress(p, &[], cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.stream(bytes, cx);
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
    }

    fn silent(&mut self, _last_record: Now, cx: &mut Cx<'_>) {
        cx.say(
            TextSeverity::Error,
            format_args!("Too long since last report, resetting"),
        );
    }
}
