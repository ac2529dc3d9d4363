//! A Nikon microscope's focus on a serial line (C++ `vrpn_nikon_controls`): its `vrpn.cfg`
//! line ([`config`]), its answers ([`answer`]), its [`Protocol`], and a simulator (`sim`, with
//! the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_nikon_controls NAME PORT
//! ```
//!
//! 9600 baud 8N1 ([`config::BAUD`]), as C++ opens it.
//!
//! # What is served
//!
//! `NAME` is an Analog with one channel, the focus position in the microscope's ticks, and an
//! Analog_Output with one channel: a client's request to set channel 0 to `v` writes
//! `fSMV<v>` (truncated to an integer). The microscope answers `qSMVA` (moving) and then
//! `oSMV` (there), and the position asked for is reported. Answers to the position request
//! `rSPR` (`aSPR<ticks>`) are reported when the position changed. Each report is stamped with
//! the arrival of its answer's first byte. A client whose remote pings the device gets the
//! channel at once, as in C++.
//!
//! # Reset and supervision
//!
//! The reset writes `rSPR` and waits up to [`RESET_WAIT`] for `aSPR<ticks>`, which is
//! reported. After [`POLL_AFTER`] without an answer the driver asks again (once a second
//! while the microscope is quiet); [`TIMEOUT`] without one sends C++'s `Timeout...` text and
//! resets the microscope on the open port.

pub mod answer;
pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::answer::{error_text, move_command, Answer, Framer, Step, ASK_FOCUS};
use self::config::BAUD;
use crate::devices::analog_output::{AnalogOutputServer, OutputRequests};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, Connection, Error};

pub use self::config::Nikon;

/// The registry entry: `vrpn_nikon_controls`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_nikon_controls"],
    parse: config::parse,
    hints: &[],
};

/// The wait for the answer to the reset's position request (C++ sleeps this long).
pub const RESET_WAIT: Duration = Duration::from_secs(1);
/// Silence after which the driver asks for the position (C++'s poll interval).
pub const POLL_AFTER: Duration = Duration::from_secs(1);
/// Silence after which the microscope is reset (C++'s time-out).
pub const TIMEOUT: Duration = Duration::from_secs(10);
/// Pause before another attempt after a failed reset.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);

/// The microscope's protocol. See the module documentation.
pub struct NikonProtocol {
    analog: AnalogServer,
    _output: AnalogOutputServer,
    /// Focus moves asked for, not yet written (the last one wins), and pings of the Analog.
    requests: OutputRequests,
    framer: Framer,
    /// Where the last move asked the focus to go (reported when it gets there).
    requested: Option<i64>,
    answer_by: Option<Instant>,
    last_answer: Option<Instant>,
    polled_at: Option<Instant>,
    last_now: Option<Instant>,
}

impl NikonProtocol {
    /// The protocol of a `vrpn_nikon_controls` entry, with its servers on `conn`.
    pub fn new(cfg: &Nikon, conn: &Connection) -> Result<NikonProtocol, Error> {
        let analog = AnalogServer::new(&cfg.name, conn, 1)?;
        let output = AnalogOutputServer::new(&cfg.name, conn, 1)?;
        // The server half checks requests (and answers one for another channel with an
        // error text); this sees each one for channel 0 as it came.
        let requests = output.watch_requests(1, Some(analog.sender()))?;
        Ok(NikonProtocol {
            analog,
            _output: output,
            requests,
            framer: Framer::new(),
            requested: None,
            answer_by: None,
            last_answer: None,
            polled_at: None,
            last_now: None,
        })
    }

    /// One answer while streaming.
    fn answer(&mut self, a: Answer, at: Now, cx: &mut Cx<'_>) {
        cx.record(at);
        self.last_answer = Some(at.mono);
        let focus = match a {
            Answer::Focus(v) => v,
            Answer::Arrived => match self.requested {
                Some(v) => v,
                None => return,
            },
            Answer::Moving => return,
            Answer::FocusError(code) | Answer::MoveError(code) => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Error response from nikon: {}", error_text(code)),
                );
                return;
            }
        };
        self.analog.set_channel(0, focus as f64);
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.analog.report_changes(Some(at.wall));
    }

    /// When the position is next asked for: [`POLL_AFTER`] after the last answer or the last
    /// request, whichever is later.
    fn poll_due(&self) -> Option<Instant> {
        let last = self.last_answer?;
        Some(self.polled_at.map_or(last, |p| p.max(last)) + POLL_AFTER)
    }

    /// Writes the move asked for and answers a ping.
    fn send_requests(&mut self, cx: &mut Cx<'_>) {
        if self.requests.take_pinged() {
            let _ = self.analog.report(Some(cx.now.wall));
        }
        if let Some((_, v)) = self.requests.take_next() {
            // As C++: the value truncated to an integer (saturating).
            let ticks = v as i64;
            let mut cmd = [0u8; 32];
            let n = move_command(ticks, &mut cmd);
            cx.write(&cmd[..n]);
            self.requested = Some(ticks);
        }
    }
}

impl Protocol for NikonProtocol {
    const KIND: &'static str = "Nikon microscope";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(BAUD))
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
        self.last_now = Some(cx.now.mono);
        self.framer.clear();
        cx.flush_input();
        cx.write(ASK_FOCUS);
        self.answer_by = Some(cx.now.mono + RESET_WAIT);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        for (i, &b) in bytes.iter().enumerate() {
            match self.framer.push(b, cx.now) {
                Step::Answer(Answer::Focus(v), at) => {
                    self.answer_by = None;
                    cx.say(
                        TextSeverity::Warning,
                        format_args!("Focus reported (this is good)"),
                    );
                    cx.say(
                        TextSeverity::Warning,
                        format_args!("reset complete (this is good)"),
                    );
                    cx.record(at);
                    self.last_answer = Some(at.mono);
                    self.polled_at = None;
                    self.analog.set_channel(0, v as f64);
                    let _ = self.analog.report(Some(at.wall));
                    // Answers that came in the same read are answers, not part of the reset.
                    self.received(&bytes[i + 1..], cx);
                    return Reset::Done;
                }
                Step::Answer(Answer::FocusError(code), _) => {
                    self.answer_by = None;
                    cx.say(
                        TextSeverity::Error,
                        format_args!("reset(): Error reading focus: {}", error_text(code)),
                    );
                    return Reset::Failed(Retry::After(RETRY_DELAY));
                }
                // Answers to earlier moves still on their way.
                Step::Answer(..) | Step::Unknown(_) | Step::More => {}
            }
        }
        self.framer.take_skipped();
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        if self.answer_by.is_some_and(|t| cx.now.mono >= t) {
            self.answer_by = None;
            cx.say(
                TextSeverity::Error,
                format_args!("reset(): No focus report from the microscope"),
            );
            return Reset::Failed(Retry::After(RETRY_DELAY));
        }
        Reset::Working
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.answer_by
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        for &b in bytes {
            match self.framer.push(b, cx.now) {
                Step::Answer(a, at) => self.answer(a, at, cx),
                Step::Unknown(_) | Step::More => {}
            }
            let skipped = self.framer.take_skipped();
            if skipped > 0 {
                cx.skipped(skipped, "Nikon", format_args!(""));
            }
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        self.send_requests(cx);
        if self.poll_due().is_some_and(|d| cx.now.mono >= d) {
            cx.write(ASK_FOCUS);
            self.polled_at = Some(cx.now.mono);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        if self.requests.is_pending() {
            return self.last_now;
        }
        self.poll_due()
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.answer_by = None;
        self.last_answer = None;
        self.polled_at = None;
    }

    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        let (cur, ts) = (cx.now.wall, last_record.wall);
        cx.say(
            TextSeverity::Error,
            format_args!(
                "Timeout... current_time={}:{}, timestamp={}:{}",
                cur.sec, cur.usec, ts.sec, ts.usec
            ),
        );
    }
}
