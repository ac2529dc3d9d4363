//! Polhemus 3SPACE trackers of the generation before the Fastrak: the original 3SPACE
//! (`vrpn_Tracker_3Space`) and the 3SPACE ISOTRAK (`vrpn_Tracker_Isotrak`). Both send the same
//! 20-byte binary record ([`record`]), found byte by byte ([`framing`]), after a reset over
//! deadlines ([`reset`]); a simulator of either is in `sim` (with the `sim` feature).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Tracker_3Space  NAME PORT BAUD
//! vrpn_Tracker_Isotrak NAME PORT BAUD [\ | /]
//! ```
//!
//! The line is 8N1 at `BAUD`, no flow control. An ISOTRAK line ending in `\` is followed by
//! extra reset commands, one per line (sent followed by CR; `*N` pauses N seconds; a line
//! ending in `\` is followed by another, one ending in `/` by Stylus lines). A line ending in
//! `/` is followed by `Stylus NAME SENSOR` lines (`SENSOR` 0 or 1), each ending in `/` if
//! another follows.
//!
//! # What is sent
//!
//! The tracker `NAME` (3SPACE: 4 sensors; ISOTRAK: 2): one `vrpn_Tracker Pos_Quat`
//! (LOW_LATENCY) per record, sensor = station − 1, stamped with the arrival of the record's
//! first byte. A Stylus `NAME` is a Button with one button, the stylus switch; a record whose
//! status byte is `@` (pressed) or `*` (released) sends its change before the pose.
//!
//! # Supervision
//!
//! 2 s without a record sends C++'s two tracker texts; the port is reopened and the tracker
//! reset ([`Supervision::TRACKER`]). A failed reset starts the next attempt at once, with a
//! stronger break.

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
use self::record::{Model, Stylus};
use self::reset::{Failure, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{ButtonServer, Connection, Error, TrackerServer};

pub use self::config::ThreeSpace;

/// The registry entry: `vrpn_Tracker_3Space` and `vrpn_Tracker_Isotrak`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_3Space", "vrpn_Tracker_Isotrak"],
    parse,
    hints: &[],
};

fn parse(
    line: &mut crate::config::ConfigLine<'_, '_>,
) -> Result<Box<dyn crate::driver::DeviceSpec>, crate::config::ConfigError> {
    if line.keyword() == "vrpn_Tracker_Isotrak" {
        config::parse_isotrak(line)
    } else {
        config::parse_3space(line)
    }
}

/// The 3SPACE / ISOTRAK protocol: its reset, its records, its reports.
pub struct ThreeSpaceProtocol {
    model: Model,
    baud: u32,
    tracker: TrackerServer,
    styluses: Vec<Option<ButtonServer>>,
    reset: ResetSequence,
    framer: Framer,
}

impl ThreeSpaceProtocol {
    /// The protocol of an entry, with its servers on `conn`.
    pub fn new(cfg: &ThreeSpace, conn: &Connection) -> Result<ThreeSpaceProtocol, Error> {
        let stations = cfg.model.stations();
        let mut styluses: Vec<Option<ButtonServer>> = (0..stations).map(|_| None).collect();
        for s in &cfg.styluses {
            let slot = styluses
                .get_mut(s.sensor as usize)
                .ok_or(Error::Unsupported(
                    "a stylus on a station the tracker lacks",
                ))?;
            *slot = Some(ButtonServer::new(&s.name, conn, 1)?);
        }
        Ok(ThreeSpaceProtocol {
            model: cfg.model,
            baud: cfg.baud,
            tracker: TrackerServer::new(&cfg.name, conn, stations)?,
            styluses,
            reset: ResetSequence::new(cfg.model, cfg.baud, cfg.reset_commands.clone()),
            framer: Framer::new(cfg.model),
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
        let label = self.model.label();
        match p {
            Progress::Working => Reset::Working,
            Progress::Started(n) => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Resetting the {label} (attempt {n})"),
                );
                Reset::Working
            }
            Progress::GoodStatus { len, after_stop } => {
                if after_stop > 0 {
                    cx.say(
                        TextSeverity::Warning,
                        format_args!("Got >={after_stop} characters after reset"),
                    );
                }
                cx.say(
                    TextSeverity::Warning,
                    format_args!("{label} gives status of {len} characters (this is good)"),
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
                    Failure::NoStatus(0) => cx.say(
                        TextSeverity::Error,
                        format_args!("{label} did not answer the status request, retrying reset"),
                    ),
                    Failure::NoStatus(n) => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "Got {n} of {} characters for status, retrying reset",
                            reset::status_len(self.model)
                        ),
                    ),
                    Failure::BadStatus(head, n) => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "Bad status report from {label} ({}), retrying reset",
                            ShownBytes(&head[..n])
                        ),
                    ),
                    Failure::NoBarrier => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "{label}: no status answer after the configuration commands, \
                             retrying reset"
                        ),
                    ),
                }
                Reset::Failed(Retry::Now)
            }
        }
    }

    fn report(&mut self, f: Framed, cx: &mut Cx<'_>) {
        let label = self.model.label();
        if let Some(why) = f.rejected {
            cx.skipped(
                u64::from(f.skipped),
                label,
                format_args!(" (last dropped: {why:?})"),
            );
        } else {
            cx.skipped(u64::from(f.skipped), label, format_args!(""));
        }
        cx.record(f.first_byte);
        let time = f.first_byte.wall;
        let p = f.pose;
        if let Some(Some(button)) = self.styluses.get(p.sensor) {
            if p.stylus != Stylus::Unknown {
                button.set_button(0, p.stylus == Stylus::Pressed);
                button.set_timestamp(time);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = button.report_changes();
            }
        }
        let _ = self.tracker.report_pose(p.sensor, time, p.pos, p.quat);
    }
}

impl Protocol for ThreeSpaceProtocol {
    const KIND: &'static str = "3Space";

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
