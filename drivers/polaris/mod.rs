//! NDI Polaris (Spectra, Vectra) optical tracker on a serial line (`vrpn_Tracker_NDI_Polaris`):
//! a reset over deadlines that loads each tool's `.rom` image ([`reset`]), then the tracker
//! polled with `TX`, its replies found byte by byte and checked by their CRC ([`reply`]); a
//! simulator in `sim` (with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_NDI_Polaris NAME PORT N
//! TOOL0.rom
//! ...
//! ```
//!
//! `N` rigid bodies (tools, 1 to 20), each on the next line by its `.rom` file (made by NDI's
//! tool software, at most 1024 bytes; relative to the server's working directory; read when
//! the device is built). The port opens at 9600 baud, 8N1; the reset moves it to 115200.
//!
//! # What is sent
//!
//! The tracker `NAME` has one sensor per tool, in the order of the lines. Each `TX` reply
//! gives, for every tool the cameras see, one `vrpn_Tracker Pos_Quat` (LOW_LATENCY) when the
//! tracker's frame number for it changed since the last report (the tracker is polled faster
//! than it measures): position in millimetres as the tracker gives it (C++ VRPN sends the
//! same numbers), quaternion as sent, stamped with the arrival of the reply's first byte. A
//! tool out of sight sends nothing.
//!
//! # Supervision
//!
//! A `TX` is sent as soon as the previous reply is in, and again after [`TX_WAIT`] without
//! one. 2 s without a good reply: C++'s two tracker texts, the port reopened, the tracker
//! reset ([`Supervision::TRACKER`]). A reply saying the tracker reset itself, or refusing
//! `TX`, resets it again.

pub mod config;
pub mod reply;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::reply::{parse_tx, ReplyReader, ToolState};
use self::reset::{Failure, Progress, ResetSequence};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{Connection, Error, TrackerServer};

pub use self::config::Polaris;

/// The registry entry: `vrpn_Tracker_NDI_Polaris`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_NDI_Polaris"],
    parse: config::parse,
    hints: &[],
};

/// The `TX` request (C++'s bytes: reply option left to the default, 0001).
pub const TX: &[u8] = b"TX \r";
/// A `TX` unanswered this long is sent again.
pub const TX_WAIT: Duration = Duration::from_millis(250);

/// The Polaris protocol: its reset, its polling, its reports.
pub struct PolarisProtocol {
    tracker: TrackerServer,
    reset: ResetSequence,
    reader: ReplyReader,
    files: Vec<String>,
    last_frame: Vec<Option<u32>>,
    tx_due: Option<Instant>,
}

impl PolarisProtocol {
    /// The protocol of an entry, with its server on `conn`.
    pub fn new(cfg: &Polaris, conn: &Connection) -> Result<PolarisProtocol, Error> {
        let n = cfg.tools.len();
        Ok(PolarisProtocol {
            tracker: TrackerServer::new(&cfg.name, conn, n.max(1))?,
            reset: ResetSequence::new(
                cfg.tools
                    .iter()
                    .map(|t| t.read())
                    .collect::<Result<_, _>>()?,
            ),
            reader: ReplyReader::new(),
            files: cfg.tools.iter().map(|t| t.file.clone()).collect(),
            last_frame: vec![None; n],
            tx_due: None,
        })
    }

    /// The tracker server the poses go out through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// The port handle the tracker gave each tool.
    pub fn handles(&self) -> &[Option<u8>] {
        self.reset.handles()
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Started(n) => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Resetting the NDI Polaris (attempt {n})"),
                );
                Reset::Working
            }
            Progress::AssumedFast => {
                cx.say(
                    TextSeverity::Normal,
                    format_args!("No answer at 9600 baud; trying 115200"),
                );
                Reset::Working
            }
            Progress::ToolRefused(t, cmd, code) => {
                cx.say(
                    TextSeverity::Error,
                    format_args!(
                        "tool {} ({}) didn't init properly: ERROR{code:02X} to {cmd:?}",
                        t, self.files[t]
                    ),
                );
                Reset::Working
            }
            Progress::Done => {
                cx.say(
                    TextSeverity::Normal,
                    format_args!("NDI Polaris tracking (this is good)"),
                );
                self.last_frame.iter_mut().for_each(|f| *f = None);
                self.send_tx(cx);
                Reset::Done
            }
            Progress::Failed(f) => {
                match f {
                    Failure::NoReply(cmd) => cx.say(
                        TextSeverity::Error,
                        format_args!("NDI Polaris did not answer {cmd:?}, retrying reset"),
                    ),
                    Failure::Refused(cmd, code) => cx.say(
                        TextSeverity::Error,
                        format_args!("NDI Polaris answered ERROR{code:02X} to {cmd:?}, retrying"),
                    ),
                    Failure::Unexpected(cmd) => cx.say(
                        TextSeverity::Error,
                        format_args!("NDI Polaris gave an unexpected reply to {cmd:?}, retrying"),
                    ),
                }
                Reset::Failed(Retry::Now)
            }
        }
    }

    fn send_tx(&mut self, cx: &mut Cx<'_>) {
        cx.write(TX);
        self.tx_due = Some(cx.now.mono + TX_WAIT);
    }
}

impl Protocol for PolarisProtocol {
    const KIND: &'static str = "NDI Polaris";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(reset::START_BAUD))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.reader.clear();
        self.tx_due = None;
        let p = self.reset.start(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        for &b in bytes {
            let Some(r) = self.reader.push(b, cx.now) else {
                continue;
            };
            let p = self.reset.reply(r.body, cx.now, cx.port());
            let done = matches!(p, Progress::Done | Progress::Failed(_));
            let out = self.progress(p, cx);
            if done {
                return out;
            }
        }
        Reset::Working
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
            let now = cx.now;
            let Some(r) = self.reader.push(b, now) else {
                continue;
            };
            cx.skipped(r.skipped as u64, "NDI Polaris", format_args!(""));
            let first_byte = r.first_byte;
            let handles = self.reset.handles();
            let (tracker, last_frame) = (&self.tracker, &mut self.last_frame);
            let parsed = parse_tx(r.body, |state| {
                let ToolState::Seen(pose) = state else {
                    return;
                };
                let Some(sensor) = handles.iter().position(|h| *h == Some(pose.handle)) else {
                    return;
                };
                if pose.frame.is_some() && last_frame[sensor] == pose.frame {
                    return;
                }
                last_frame[sensor] = pose.frame;
                let _ = tracker.report_pose(sensor, first_byte.wall, pose.pos, pose.quat);
            });
            match parsed {
                Ok(()) => {
                    cx.record(first_byte);
                    self.send_tx(cx);
                }
                Err(_) if r.body.starts_with(b"RESET") || r.body.starts_with(b"ERROR") => {
                    cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "NDI Polaris answered '{}' to TX, resetting",
                            ShownBytes(r.body)
                        ),
                    );
                    cx.reset();
                    return;
                }
                Err(why) => {
                    let n = r.body.len() as u64 + 5;
                    cx.skipped(n, "NDI Polaris", format_args!(" (not a TX reply: {why:?})"));
                }
            }
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.tx_due.is_some_and(|t| cx.now.mono >= t) {
            // What a broken reply left in the reader is trimmed off the next one.
            self.send_tx(cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.tx_due
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.reader.clear();
        self.tx_due = None;
    }
}
