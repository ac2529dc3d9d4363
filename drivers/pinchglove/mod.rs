//! The Fakespace Pinch Glove system (two gloves, ten finger contacts) on a serial line: its
//! `vrpn.cfg` line ([`config`]), its messages ([`message`]), its [`Protocol`] run by the
//! shared [`Lifecycle`](crate::driver::Lifecycle), and a device simulator (`sim`, with the
//! `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Button_PinchGlove NAME PORT BAUD
//! ```
//!
//! The line is 8N1 at `BAUD` (9600 is usual).
//!
//! # What is sent
//!
//! `NAME` is a Button with ten buttons: 0-4 the right hand's thumb to little finger, 5-9 the
//! left hand's. A finger is pressed while it touches another finger (so a single button is
//! never pressed alone). Each touch message sends one `vrpn_Button Change` per button that
//! changed (toggle modes a client sets are applied, as in C++), stamped with the arrival of
//! the message's first byte.
//!
//! # Reset and supervision
//!
//! The reset writes `T0` (time stamps off) and waits up to [`ANSWER_LIMIT`] for the answer
//! `0x82 '0' 0x8F`; without one it writes `T0` again (a warning text at the first failure and
//! every 20th). Touch messages that arrive meanwhile are reported. The glove sends only when a
//! contact changes, so after [`IDLE_PROBE`] without a byte the driver writes `T0` again as a
//! probe: no answer within [`PROBE_TIMEOUT`] sends an error text and resets the glove (which
//! retries until it answers). A touch message with time stamps (the glove was switched to
//! that mode) sends C++'s error text and resets it. A port that fails is reopened by the
//! serial layer.
//!
//! # Differences from C++ VRPN
//!
//! * C++ writes `T0` and reads the answer in a loop that blocks the whole server until the
//!   glove answers (forever, if it is off); here the reset is a deadline, and other devices
//!   keep running.
//! * The idle probe: C++ never notices a glove that was switched off.
//! * Each touch message is reported with its own first-byte time; C++ reports once per
//!   server loop (intermediate states of a burst are lost) with the loop's time.
//! * Damaged messages (odd pair counts, bytes out of range, a lost end byte) are dropped and
//!   reported once a second; C++ can read a damaged message as contacts, or block waiting for
//!   the second byte of a pair.

pub mod config;
pub mod message;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::message::{pressed, Found, Framer, BUTTONS};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{ButtonServer, Connection, Error};

pub use self::config::PinchGlove;

/// The registry entry: `vrpn_Button_PinchGlove`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Button_PinchGlove"],
    parse: config::parse,
    hints: &[],
};

/// The command "time stamps off", the reset and the probe.
pub const TIME_STAMPS_OFF: &[u8] = b"T0";
/// Time the glove has to answer `T0` during a reset.
pub const ANSWER_LIMIT: Duration = Duration::from_millis(100);
/// Silence after which the glove is probed with `T0`.
pub const IDLE_PROBE: Duration = Duration::from_secs(2);
/// Time the glove has to answer the probe.
pub const PROBE_TIMEOUT: Duration = Duration::from_secs(1);
/// At most one note about messages with unknown start bytes per this interval.
const NOTE_INTERVAL: Duration = Duration::from_secs(1);

/// The Pinch Glove's protocol. See the module documentation.
pub struct PinchGloveProtocol {
    baud: u32,
    buttons: ButtonServer,
    framer: Framer,
    answer_by: Option<Instant>,
    failed_attempts: u32,
    last_heard: Option<Instant>,
    probe_by: Option<Instant>,
    probes: u64,
    last_unknown_note: Option<Instant>,
}

impl PinchGloveProtocol {
    /// The protocol of a `vrpn_Button_PinchGlove` entry, with its buttons on `conn`.
    pub fn new(cfg: &PinchGlove, conn: &Connection) -> Result<PinchGloveProtocol, Error> {
        Ok(PinchGloveProtocol {
            baud: cfg.baud,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            framer: Framer::new(),
            answer_by: None,
            failed_attempts: 0,
            last_heard: None,
            probe_by: None,
            probes: 0,
            last_unknown_note: None,
        })
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// Bytes skipped while looking for messages, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    /// Idle probes written since construction.
    pub fn probes(&self) -> u64 {
        self.probes
    }

    /// Handles one byte: reports a touch message it completes, notes answers and problems.
    fn byte(&mut self, b: u8, resetting: bool, cx: &mut Cx<'_>) -> Step {
        match self.framer.push(b, cx.now) {
            None => Step::Go,
            Some(Found::Touch {
                left,
                right,
                first_byte,
                skipped,
            }) => {
                cx.skipped(u64::from(skipped), "PinchGlove", format_args!(""));
                cx.record(first_byte);
                for (i, p) in pressed(left, right).into_iter().enumerate() {
                    self.buttons.set_button(i, p);
                }
                self.buttons.set_timestamp(first_byte.wall);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.buttons.report_changes();
                Step::Go
            }
            Some(Found::Text { zero_answer }) => {
                if zero_answer && resetting {
                    return Step::Answered;
                }
                if zero_answer {
                    self.probe_by = None;
                }
                Step::Go
            }
            Some(Found::Timed) if resetting => Step::Go,
            Some(Found::Timed) => {
                cx.say(
                    TextSeverity::Error,
                    format_args!("vrpn_Button_PinchGlove message start byte: time stamped byte!"),
                );
                cx.reset();
                Step::Stop
            }
            Some(Found::Unknown(start)) => {
                let now = cx.now.mono;
                if self
                    .last_unknown_note
                    .map_or(true, |t| now >= t + NOTE_INTERVAL)
                {
                    self.last_unknown_note = Some(now);
                    cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "vrpn_Button_PinchGlove wrong message start byte (0x{start:02X})"
                        ),
                    );
                }
                Step::Go
            }
        }
    }
}

/// What reading a byte led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Go,
    Answered,
    Stop,
}

impl Protocol for PinchGloveProtocol {
    const KIND: &'static str = "PinchGlove";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.failed_attempts == 0 {
            // Stale input (from before the port opened) goes; a retry keeps what comes, since
            // touch messages during the reset are reported.
            cx.flush_input();
        }
        cx.write(TIME_STAMPS_OFF);
        self.answer_by = Some(cx.now.mono + ANSWER_LIMIT);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        for (i, &b) in bytes.iter().enumerate() {
            if self.byte(b, true, cx) == Step::Answered {
                if self.failed_attempts > 0 {
                    cx.say(
                        TextSeverity::Normal,
                        format_args!(
                            "vrpn_Button_PinchGlove: the glove answered after {} attempts",
                            self.failed_attempts + 1
                        ),
                    );
                }
                self.failed_attempts = 0;
                self.answer_by = None;
                self.last_heard = Some(cx.now.mono);
                self.received(&bytes[i + 1..], cx);
                return Reset::Done;
            }
        }
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.failed_attempts += 1;
        if self.failed_attempts % 20 == 1 {
            cx.say(
                TextSeverity::Warning,
                format_args!(
                    "vrpn_Button_PinchGlove: no answer to T0 (attempt {}; is the glove on?), \
                     retrying",
                    self.failed_attempts
                ),
            );
        }
        Reset::Failed(Retry::Now)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.answer_by
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        if !bytes.is_empty() {
            self.last_heard = Some(cx.now.mono);
        }
        for &b in bytes {
            if self.byte(b, false, cx) == Step::Stop {
                return;
            }
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.probe_by
            .or_else(|| self.last_heard.map(|t| t + IDLE_PROBE))
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        let now = cx.now.mono;
        if let Some(by) = self.probe_by {
            if now >= by {
                cx.say(
                    TextSeverity::Error,
                    format_args!("vrpn_Button_PinchGlove: no answer to a T0 probe, resetting"),
                );
                cx.reset();
            }
            return;
        }
        if self.last_heard.is_some_and(|t| now >= t + IDLE_PROBE) {
            cx.write(TIME_STAMPS_OFF);
            self.probes += 1;
            self.probe_by = Some(now + PROBE_TIMEOUT);
        }
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.answer_by = None;
        self.last_heard = None;
        self.probe_by = None;
    }
}
