//! The Global Haptics Orb on a serial line (`vrpn_GlobalHapticsOrb`): 30 buttons, a
//! thumbwheel and a trackball, each event one byte ([`event`]); a reset over a deadline; a
//! simulator in `sim` (with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_GlobalHapticsOrb NAME PORT BAUD
//! ```
//!
//! 8N1 at `BAUD` (19200).
//!
//! # What is sent
//!
//! `NAME` is a Button (30 buttons), an Analog (3 channels: the thumbwheel and the ball's two
//! axes, each the sum of its turns in revolutions held within −1…1) and a Dial (3 dials: the
//! same turns, as they happen). Each event byte sends its change, stamped with its arrival.
//!
//! # Supervision
//!
//! The reset writes `81` and waits up to [`RESET_WAIT`] for the Orb's `FC`. After
//! [`PROBE_AFTER`] without a byte the driver writes `81` again (the Orb answers `FC`); after
//! 10 s, C++'s text `Too long since last report, resetting` and a reset.

pub mod config;
pub mod event;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::event::{channel_after, decode, Event, BUTTONS, DIALS, RESET, RESET_ANSWER};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, DialServer, Error};

pub use self::config::Orb;

/// The registry entry: `vrpn_GlobalHapticsOrb`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_GlobalHapticsOrb"],
    parse: config::parse,
    hints: &[],
};

/// The wait for the Orb's answer to the reset byte (C++'s).
pub const RESET_WAIT: Duration = Duration::from_secs(2);
/// Silence after which the driver asks the Orb to answer (C++'s poll interval).
pub const PROBE_AFTER: Duration = Duration::from_secs(5);
/// Silence after which the Orb is reset (C++'s time-out).
pub const TIMEOUT: Duration = Duration::from_secs(10);

/// The Orb protocol: its reset, its events, its reports.
pub struct OrbProtocol {
    baud: u32,
    buttons: ButtonServer,
    analog: AnalogServer,
    dials: DialServer,
    channels: [f64; DIALS],
    answer_by: Option<Instant>,
    probe_at: Option<Instant>,
}

impl OrbProtocol {
    /// The protocol of an entry, with its servers on `conn`.
    pub fn new(cfg: &Orb, conn: &Connection) -> Result<OrbProtocol, Error> {
        Ok(OrbProtocol {
            baud: cfg.baud,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            analog: AnalogServer::new(&cfg.name, conn, DIALS)?,
            dials: DialServer::new(&cfg.name, conn, DIALS)?,
            channels: [0.0; DIALS],
            answer_by: None,
            probe_at: None,
        })
    }

    fn event(&mut self, e: Event, at: Now) {
        match e {
            Event::Button(i, pressed) => {
                self.buttons.set_button(i, pressed);
                self.buttons.set_timestamp(at.wall);
                let _ = self.buttons.report_changes();
            }
            Event::Turn(i, rev) => {
                self.channels[i] = channel_after(self.channels[i], rev);
                self.analog.set_channel(i, self.channels[i]);
                let _ = self.analog.report_changes(Some(at.wall));
                self.dials.add_rotation(i, rev);
                self.dials.set_timestamp(at.wall);
                let _ = self.dials.report_changes();
            }
            Event::Status => {}
        }
    }
}

impl Protocol for OrbProtocol {
    const KIND: &'static str = "Global Haptics Orb";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision {
            watchdog: Some(TIMEOUT),
            on_silence: Recovery::Reset,
            pause: None,
            skip_note_interval: Duration::from_secs(1),
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.probe_at = None;
        cx.flush_input();
        cx.write(&[RESET]);
        self.answer_by = Some(cx.now.mono + RESET_WAIT);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let Some(at) = bytes.iter().position(|&b| b == RESET_ANSWER) else {
            return Reset::Working;
        };
        self.answer_by = None;
        self.probe_at = Some(cx.now.mono + PROBE_AFTER);
        cx.say(
            TextSeverity::Normal,
            format_args!("vrpn_GlobalHapticsOrb::reset(): Reset complete (this is good)"),
        );
        // Events the Orb sent right after its answer can share the read: they are events.
        self.received(&bytes[at + 1..], cx);
        Reset::Done
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.answer_by.is_some_and(|t| cx.now.mono >= t) {
            self.answer_by = None;
            cx.say(
                TextSeverity::Error,
                format_args!("vrpn_GlobalHapticsOrb::reset(): No response from Orb"),
            );
            return Reset::Failed(Retry::Now);
        }
        Reset::Working
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.answer_by
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            match decode(b) {
                Some(e) => {
                    cx.record(cx.now);
                    self.event(e, cx.now);
                }
                None => cx.skipped(
                    1,
                    "vrpn_GlobalHapticsOrb",
                    format_args!(" (unknown byte {b:02X})"),
                ),
            }
        }
        self.probe_at = Some(cx.now.mono + PROBE_AFTER);
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.probe_at.is_some_and(|t| cx.now.mono >= t) {
            cx.write(&[RESET]);
            self.probe_at = Some(cx.now.mono + PROBE_AFTER);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.probe_at
    }

    fn stopped(&mut self) {
        self.answer_by = None;
        self.probe_at = None;
    }

    fn silent(&mut self, _last_record: Now, cx: &mut Cx<'_>) {
        cx.say(
            TextSeverity::Error,
            format_args!("Too long since last report, resetting"),
        );
    }
}
