//! Crossbow RGA300CA inclinometer / rate gyro on a serial line (`vrpn_Tracker_Crossbow`):
//! a reset over deadlines ([`reset`]), then the device polled for 24-byte packets found byte
//! by byte ([`packet`]); a simulator in `sim` (with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_Crossbow NAME PORT BAUD [G_RANGE [ANGULAR_RANGE]]
//! ```
//!
//! 8N1 at `BAUD` (38400 for the RGA300CA). `G_RANGE` is the linear acceleration
//! sensitivity in g (2.0 unless given), `ANGULAR_RANGE` the angular rate sensitivity in °/s
//! (100 unless given); both scale the raw values as C++ VRPN scales them.
//!
//! # What is sent
//!
//! The tracker `NAME` has one sensor. For each packet, three messages (LOW_LATENCY), all
//! stamped with the arrival of the packet's first byte: `vrpn_Tracker Pos_Quat` (position 0,
//! orientation from pitch and roll, no yaw), `vrpn_Tracker Acceleration` (m/s², no angular
//! part) and `vrpn_Tracker Velocity` (no linear part; the rotation of one second at the yaw
//! rate, about z). The values are C++ VRPN's to the bit.
//!
//! # Supervision
//!
//! `G` asks for a packet as soon as the previous one is in, and again after [`G_WAIT`]
//! without one. 2 s without a packet: C++'s two tracker texts, the port reopened, the
//! device reset ([`Supervision::TRACKER`]).

pub mod config;
pub mod packet;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::packet::Framer;
use self::reset::{Failure, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{Connection, Error, TrackerServer};

pub use self::config::Crossbow;

/// The registry entry: `vrpn_Tracker_Crossbow`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_Crossbow"],
    parse: config::parse,
    hints: &[],
};

/// A `G` unanswered this long is sent again.
pub const G_WAIT: Duration = Duration::from_millis(100);

/// The Crossbow protocol: its reset, its polling, its reports.
pub struct CrossbowProtocol {
    baud: u32,
    g_range: f32,
    ar_range: f32,
    tracker: TrackerServer,
    reset: ResetSequence,
    framer: Framer,
    g_due: Option<Instant>,
}

impl CrossbowProtocol {
    /// The protocol of an entry, with its server on `conn`.
    pub fn new(cfg: &Crossbow, conn: &Connection) -> Result<CrossbowProtocol, Error> {
        Ok(CrossbowProtocol {
            baud: cfg.baud,
            g_range: cfg.g_range,
            ar_range: cfg.ar_range,
            tracker: TrackerServer::new(&cfg.name, conn, 1)?,
            reset: ResetSequence::new(),
            framer: Framer::new(),
            g_due: None,
        })
    }

    /// The tracker server the reports go out through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// The device's serial number, once reset.
    pub fn serial(&self) -> u32 {
        self.reset.serial()
    }

    fn ask(&mut self, cx: &mut Cx<'_>) {
        cx.write(b"G");
        self.g_due = Some(cx.now.mono + G_WAIT);
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Started(n) => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Resetting the Crossbow (attempt {n})"),
                );
                Reset::Working
            }
            Progress::Done => {
                cx.say(
                    TextSeverity::Normal,
                    format_args!(
                        "Crossbow serial {} version '{}' (this is good)",
                        self.reset.serial(),
                        ShownBytes(self.reset.version())
                    ),
                );
                self.framer.clear();
                self.ask(cx);
                Reset::Done
            }
            Progress::Failed(f) => {
                match f {
                    Failure::NoAnswer => cx.say(
                        TextSeverity::Error,
                        format_args!("Crossbow not responding to stimulus, retrying reset"),
                    ),
                    Failure::BadAnswer(a) => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "Crossbow gave unexpected ping response ({}), retrying reset",
                            ShownBytes(&a)
                        ),
                    ),
                    Failure::BadChecksum => cx.say(
                        TextSeverity::Error,
                        format_args!("Crossbow gave invalid serial number checksum, retrying"),
                    ),
                }
                Reset::Failed(Retry::Now)
            }
        }
    }
}

impl Protocol for CrossbowProtocol {
    const KIND: &'static str = "Crossbow";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.g_due = None;
        let p = self.reset.start(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.received(bytes, cx.now);
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
            let Some(f) = self.framer.push(b, cx.now) else {
                continue;
            };
            cx.skipped(u64::from(f.skipped), "Crossbow", format_args!(""));
            cx.record(f.first_byte);
            let r = f.packet.report(self.g_range, self.ar_range);
            let t = f.first_byte.wall;
            let _ = self.tracker.report_pose(0, t, [0.0; 3], r.quat);
            let _ = self
                .tracker
                .report_acceleration(0, t, r.acc, [0.0, 0.0, 0.0, 1.0], 1.0);
            let _ = self
                .tracker
                .report_velocity(0, t, [0.0; 3], r.vel_quat, 1.0);
            self.ask(cx);
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.g_due.is_some_and(|t| cx.now.mono >= t) {
            self.ask(cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.g_due
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
        self.g_due = None;
    }
}
