//! The Logitech 3D mouse and head tracker (`vrpn_Tracker_3DMouse`): an ultrasonic tracker
//! whose control unit answers one 16-byte Euler record per request. Its `vrpn.cfg` line
//! ([`config`]), its records ([`record`]), its reset over deadlines ([`reset`]), its
//! [`Protocol`] run by the shared [`Lifecycle`](crate::driver::Lifecycle), and a simulator
//! (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_3DMouse NAME PORT BAUD [FILTER_COUNT]
//! ```
//!
//! 8N1 at `BAUD` (19200). `FILTER_COUNT` (1–5) is the control unit's filter count; above 1 it
//! is set at each reset.
//!
//! # Reset
//!
//! `*R`, then after [`reset::SETTLE`] the diagnostics request `*` 05, sent again every
//! [`reset::STATUS_WAIT`] while unanswered; its two-byte answer must report every self-test
//! passed (`BF 3F`). Then `2A 24 02 07 n` sets a filter count above 1, and `*d` asks for the
//! first record. No answer within [`reset::GIVE_UP`] of `*R`, or a failed test: an error text
//! naming it, and the port is reopened and the reset started over (as C++ does).
//!
//! # What is sent
//!
//! `NAME` is a Tracker with one sensor and a Button with 5 buttons (0 the stand's button,
//! 1 suspend, 2 left, 3 middle, 4 right). For each record: the buttons that changed, then a
//! `vrpn_Tracker Pos_Quat` (unless the mouse is out of range), all stamped with the arrival
//! of the record's first byte. Position in metres (the device's x, −z, y); orientation
//! from pitch, yaw and roll (see [`record::Record::orientation`]).
//!
//! # Supervision
//!
//! `*d` asks for the next record as soon as one is in (one request in flight), and again
//! after [`answer_wait`] without an answer. 2 s without a record: the watchdog's texts, the
//! port is reopened and the device reset.

pub mod config;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::record::{Framed, Framer, BUTTONS};
use self::reset::{failed_tests, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{ButtonServer, Connection, Error, TrackerServer};

pub use self::config::ThreeDMouse;

/// The registry entry: `vrpn_Tracker_3DMouse`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_3DMouse"],
    parse: config::parse,
    hints: &[],
};

/// The request for one record.
pub const REQUEST: &[u8] = b"*d";

/// How long a request for a record may go unanswered before it is sent again: twice the
/// record's time on the line at `baud`, and 50 ms.
pub fn answer_wait(baud: u32) -> Duration {
    let record_us = record::RECORD_LEN as u64 * 10_000_000 / u64::from(baud.max(1));
    Duration::from_micros(2 * record_us) + Duration::from_millis(50)
}

/// The 3D mouse's protocol. See the module documentation.
pub struct ThreeDMouseProtocol {
    baud: u32,
    tracker: TrackerServer,
    buttons: ButtonServer,
    reset: ResetSequence,
    framer: Framer,
    ask_again: Option<Instant>,
    requests: u64,
}

impl ThreeDMouseProtocol {
    /// The protocol of a `vrpn_Tracker_3DMouse` entry, with its servers on `conn`.
    pub fn new(cfg: &ThreeDMouse, conn: &Connection) -> Result<ThreeDMouseProtocol, Error> {
        Ok(ThreeDMouseProtocol {
            baud: cfg.baud,
            tracker: TrackerServer::new(&cfg.name, conn, 1)?,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            reset: ResetSequence::new(cfg.filter_count),
            framer: Framer::new(),
            ask_again: None,
            requests: 0,
        })
    }

    /// The tracker server.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// Bytes skipped looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    /// Records asked for (`*d` written), since construction.
    pub fn requests(&self) -> u64 {
        self.requests
    }

    fn ask(&mut self, cx: &mut Cx<'_>) {
        cx.write(REQUEST);
        self.requests += 1;
        self.ask_again = Some(cx.now.mono + answer_wait(self.baud));
    }

    fn report(&mut self, f: Framed, cx: &mut Cx<'_>) {
        cx.skipped(u64::from(f.skipped), "3DMouse", format_args!(""));
        cx.record(f.first_byte);
        let time = f.first_byte.wall;
        let r = f.record;
        for (i, pressed) in r.buttons().into_iter().enumerate() {
            self.buttons.set_button(i, pressed);
        }
        self.buttons.set_timestamp(time);
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.buttons.report_changes();
        if !r.out_of_range() {
            let _ = self
                .tracker
                .report_pose(0, time, r.position(), r.orientation());
        }
    }

    fn progress(&mut self, p: Progress, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Started => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Resetting the 3DMouse..."),
                );
                Reset::Working
            }
            Progress::Done { rest } => {
                cx.say(
                    TextSeverity::Normal,
                    format_args!("3DMouse gives status (this is good)"),
                );
                cx.say(
                    TextSeverity::Normal,
                    format_args!("Reset Completed (this is good)"),
                );
                self.framer.clear();
                self.ask(cx);
                // Whatever came after the answer in its read is the stream's.
                self.received(&bytes[rest.min(bytes.len())..], cx);
                Reset::Done
            }
            Progress::NoAnswer => {
                cx.say(
                    TextSeverity::Error,
                    format_args!(
                        "3DMouse: no answer to the status request ({} asked), reopening the \
                         port and resetting",
                        self.reset.asked()
                    ),
                );
                Reset::Failed(Retry::Reopen)
            }
            Progress::Failed(answer) => {
                let mut failed = [""; reset::TESTS.len()];
                let mut n = 0;
                for (slot, name) in failed.iter_mut().zip(failed_tests(answer)) {
                    *slot = name;
                    n += 1;
                }
                cx.say(
                    TextSeverity::Error,
                    format_args!(
                        "Bad status report from 3DMouse ({}: {} failed), retrying reset",
                        ShownBytes(&answer),
                        failed[..n].join(", ")
                    ),
                );
                Reset::Failed(Retry::Reopen)
            }
        }
    }
}

impl Protocol for ThreeDMouseProtocol {
    const KIND: &'static str = "3DMouse";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.ask_again = None;
        let p = self.reset.start(cx.now, cx.port());
        self.progress(p, &[], cx)
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.received(bytes, cx.port());
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
        let mut answered = false;
        for &b in bytes {
            if let Some(f) = self.framer.push(b, cx.now) {
                self.report(f, cx);
                answered = true;
            }
        }
        // One request per read that completed records and holds no part of another: a
        // slow reader that found several answers at once asks once, so no more than one
        // request stays in flight.
        if answered && !self.framer.is_partial() {
            self.ask(cx);
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.ask_again.is_some_and(|t| cx.now.mono >= t) {
            self.ask(cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.ask_again
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
        self.ask_again = None;
    }

    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        let quiet = cx.now.mono.saturating_duration_since(last_record.mono);
        cx.say(
            TextSeverity::Error,
            format_args!(
                "3DMouse: no record for {:.1} s ({} requests unanswered)",
                quiet.as_secs_f64(),
                quiet.as_millis() / answer_wait(self.baud).as_millis().max(1)
            ),
        );
        cx.say(
            TextSeverity::Error,
            format_args!(
                "3DMouse failed, trying to reset (Try power cycle if more than 4 attempts made)"
            ),
        );
    }
}
