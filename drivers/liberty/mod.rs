//! Polhemus Liberty and Patriot (and Liberty Latus records) on a serial line
//! (`vrpn_Tracker_Liberty`): binary records ([`record`]) found byte by byte ([`framing`])
//! after a reset over deadlines ([`reset`]); a simulator in `sim` (with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_Liberty NAME PORT BAUD [WHOAMI_LEN] [\ | /]
//! ```
//!
//! 8N1 at `BAUD`, no flow control (a Liberty on USB shows as a serial port too, and the rate
//! is then ignored by the tracker). `WHOAMI_LEN` is the length of the tracker's WhoAmI answer
//! (195 unless given, at most 1024). A line ending in `\` is followed by extra reset commands
//! (one per line, sent followed by CR; `*N` pauses N seconds; the last may end in `/`); a
//! line ending in `/` by `Stylus NAME SENSOR` lines (`SENSOR` 0 to 7), each ending in `/` if
//! another follows.
//!
//! # What is sent
//!
//! The tracker `NAME` has 8 sensors: one `vrpn_Tracker Pos_Quat` (LOW_LATENCY) per record,
//! sensor = station − 1, position in metres (inches × 2.54 / 100), quaternion as sent,
//! stamped with the arrival of the record's first byte. A Stylus `NAME` is a Button with two
//! buttons; button 0 is the stylus switch, its change sent before the pose.
//!
//! # Supervision
//!
//! 2 s without a record: C++'s two tracker texts, the port reopened, the tracker reset
//! ([`Supervision::TRACKER`]). A failed reset starts the next attempt at once, with a
//! stronger break (Ctrl-Y from the third).

pub mod config;
pub mod framing;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::Instant;

use self::framing::{Framed, Framer};
use self::record::STATIONS;
use self::reset::{Failure, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Hint, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{ButtonServer, Connection, Error, TrackerServer};

pub use self::config::Liberty;

/// The registry entry: `vrpn_Tracker_Liberty`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_Liberty"],
    parse: config::parse,
    hints: &[Hint {
        keyword: "vrpn_Tracker_LibertyHS",
        text: "the Liberty Latus on USB needs libusb, which this server does not use; a \
               Liberty or Patriot that shows as a serial port is vrpn_Tracker_Liberty",
    }],
};

/// The Liberty / Patriot protocol: its reset, its records, its reports.
pub struct LibertyProtocol {
    baud: u32,
    tracker: TrackerServer,
    styluses: Vec<Option<ButtonServer>>,
    reset: ResetSequence,
    framer: Framer,
    whoami_len: usize,
}

impl LibertyProtocol {
    /// The protocol of an entry, with its servers on `conn`.
    pub fn new(cfg: &Liberty, conn: &Connection) -> Result<LibertyProtocol, Error> {
        let mut styluses: Vec<Option<ButtonServer>> = (0..STATIONS).map(|_| None).collect();
        let mut has = [false; STATIONS];
        for s in &cfg.styluses {
            let i = s.sensor as usize;
            let slot = styluses.get_mut(i).ok_or(Error::Unsupported(
                "a stylus on a station the tracker lacks",
            ))?;
            *slot = Some(ButtonServer::new(&s.name, conn, 2)?);
            has[i] = true;
        }
        Ok(LibertyProtocol {
            baud: cfg.baud,
            tracker: TrackerServer::new(&cfg.name, conn, STATIONS)?,
            styluses,
            reset: ResetSequence::new(cfg.baud, cfg.whoami_len, has, cfg.reset_commands.clone()),
            framer: Framer::new(has),
            whoami_len: cfg.whoami_len,
        })
    }

    /// The tracker server the poses go out through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// Reset attempts since the last good one.
    pub fn reset_attempts(&self) -> u32 {
        self.reset.attempts()
    }

    /// Bytes dropped looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Started(n) => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Resetting the tracker (attempt {n})"),
                );
                Reset::Working
            }
            Progress::GoodStatus { len, .. } => {
                // Bytes after the break are expected: `P` asks for one record.
                if len != self.whoami_len {
                    cx.say(
                        TextSeverity::Normal,
                        format_args!("Got {len} of {} characters for status", self.whoami_len),
                    );
                }
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Liberty/Isense gives status (this is good)"),
                );
                Reset::Working
            }
            Progress::Done => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Reset Completed (this is good)"),
                );
                Reset::Done
            }
            Progress::Failed(f) => {
                match f {
                    Failure::NoAnswer => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "Liberty did not answer WhoAmI (is it on, at {} baud?), retrying \
                             reset",
                            self.baud
                        ),
                    ),
                    Failure::BadStatus(head, n) => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "Bad status report from Liberty ({}), retrying reset",
                            ShownBytes(&head[..n])
                        ),
                    ),
                }
                Reset::Failed(Retry::Now)
            }
        }
    }

    fn report(&mut self, f: Framed, cx: &mut Cx<'_>) {
        match f.rejected {
            Some(why) => cx.skipped(
                u64::from(f.skipped),
                "Liberty",
                format_args!(" (last dropped: {why:?})"),
            ),
            None => cx.skipped(u64::from(f.skipped), "Liberty", format_args!("")),
        }
        cx.record(f.first_byte);
        let time = f.first_byte.wall;
        let p = f.pose;
        if let (Some(Some(button)), Some(pressed)) = (self.styluses.get(p.sensor), p.stylus) {
            button.set_button(0, pressed);
            button.set_timestamp(time);
            // A failed send is the connection's business (it reports and drops the peer).
            let _ = button.report_changes();
        }
        let _ = self.tracker.report_pose(p.sensor, time, p.pos, p.quat);
    }
}

impl Protocol for LibertyProtocol {
    const KIND: &'static str = "Liberty";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.start(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.received(bytes, cx.now, cx.port());
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
            if let Some(f) = self.framer.push(b, cx.now) {
                self.report(f, cx);
            }
        }
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
    }
}
