//! The Fraunhofer IMK AD-Box (and the Fakespace Cubic Mouse, built on it) on a serial line
//! (C++ `vrpn_ADBox`): its `vrpn.cfg` line ([`config`]), its answers ([`frame`]), its
//! [`Protocol`], and a simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_ADBox NAME PORT BAUD
//! ```
//!
//! 8N1 at `BAUD`.
//!
//! # Reset: finding the box's layout
//!
//! The box sends one answer per request byte `U`. The reset writes `U` and counts the bytes
//! of the answer until [`REPLY_WAIT`] passes without one: 14, 18 or 19 bytes tell the layout
//! ([`frame::Layout`]); any other count sends C++'s warning `trying to detect ad-box` and the
//! reset is tried again after [`RETRY_DELAY`]. The detected answer is reported.
//!
//! # What is served
//!
//! `NAME` is a Button (16 or 24 buttons, C++'s toggle modes applied) and an Analog (6 or 8
//! channels, 0..=1 through C++'s flicker filter). Each answer is decoded, reported (changes
//! only) with the arrival of its first byte, and the next `U` written.
//!
//! # Supervision
//!
//! An answer whose next byte does not come within [`REPLY_WAIT`] (of the request, then of
//! each byte: C++'s time-out per byte) is dropped and `U` written again.
//! An answer whose analog high bytes exceed 3 (out of step with the requests, after line
//! noise) is dropped, and the next `U` is written once the line has been quiet for
//! [`QUIET`]. [`TIMEOUT`] without an answer starts the detection again.

pub mod config;
pub mod frame;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::frame::{Filter, Layout, MAX_ANSWER, REQUEST};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::AdBox;

/// The registry entry: `vrpn_ADBox`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_ADBox"],
    parse: config::parse,
    hints: &[],
};

/// The longest wait for the next byte of an answer (C++'s read time-out).
pub const REPLY_WAIT: Duration = Duration::from_millis(200);
/// The pause before another detection (C++ sleeps 1 s).
pub const RETRY_DELAY: Duration = Duration::from_secs(1);
/// Quiet on the line that ends a resynchronisation.
pub const QUIET: Duration = Duration::from_millis(20);
/// Silence after which the layout is detected again.
pub const TIMEOUT: Duration = Duration::from_secs(1);
/// Bytes counted at most in the detection (C++'s limit).
const DETECT_MAX: usize = 100;

/// The box's protocol. See the module documentation.
pub struct AdBoxProtocol {
    baud: u32,
    buttons: ButtonServer,
    analog: AnalogServer,
    filter: Filter,
    layout: Option<Layout>,
    answer: [u8; MAX_ANSWER],
    got: usize,
    first: Option<Now>,
    /// Bytes of the detection's answer.
    detected: usize,
    /// When the detection ends, or a pending answer is given up.
    wait_until: Option<Instant>,
    /// Dropping bytes until the line is quiet until then.
    resync_until: Option<Instant>,
}

impl AdBoxProtocol {
    /// The protocol of a `vrpn_ADBox` entry, with its servers on `conn`.
    pub fn new(cfg: &AdBox, conn: &Connection) -> Result<AdBoxProtocol, Error> {
        Ok(AdBoxProtocol {
            baud: cfg.baud,
            buttons: ButtonServer::new(&cfg.name, conn, 0)?,
            analog: AnalogServer::new(&cfg.name, conn, 0)?,
            filter: Filter::new(),
            layout: None,
            answer: [0; MAX_ANSWER],
            got: 0,
            first: None,
            detected: 0,
            wait_until: None,
            resync_until: None,
        })
    }

    /// The layout found by the last detection.
    pub fn layout(&self) -> Option<Layout> {
        self.layout
    }

    fn ask(&mut self, cx: &mut Cx<'_>) {
        self.got = 0;
        self.first = None;
        cx.write(&[REQUEST]);
        self.wait_until = Some(cx.now.mono + REPLY_WAIT);
    }

    /// A whole answer: reported if it can be one, else the line is resynchronised.
    fn answer(&mut self, layout: Layout, cx: &mut Cx<'_>) {
        let at = self.first.unwrap_or(cx.now);
        let answer = &self.answer[..layout.len];
        if !layout.plausible(answer) {
            cx.skipped(
                layout.len as u64,
                "vrpn_ADBox",
                format_args!(" (an answer out of step)"),
            );
            self.got = 0;
            self.first = None;
            self.wait_until = None;
            self.resync_until = Some(cx.now.mono + QUIET);
            return;
        }
        cx.record(at);
        for i in 0..layout.buttons() {
            self.buttons.set_button(i, layout.pressed(answer, i));
        }
        for c in 0..layout.channels() {
            let v = self.filter.value(c, layout.raw(answer, c));
            self.analog.set_channel(c, v);
        }
        self.filter.next_frame();
        // A failed send is the connection's business (it reports and drops the peer).
        self.buttons.set_timestamp(at.wall);
        let _ = self.buttons.report_changes();
        let _ = self.analog.report_changes(Some(at.wall));
    }
}

impl Protocol for AdBoxProtocol {
    const KIND: &'static str = "vrpn_ADBox";

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
        cx.flush_output();
        cx.flush_input();
        self.detected = 0;
        self.resync_until = None;
        self.ask(cx);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        if self.first.is_none() {
            self.first = Some(cx.now);
        }
        for &b in bytes {
            if self.detected < MAX_ANSWER {
                self.answer[self.detected] = b;
            }
            self.detected = (self.detected + 1).min(DETECT_MAX);
        }
        self.wait_until = Some(cx.now.mono + REPLY_WAIT);
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        if !self.wait_until.is_some_and(|t| cx.now.mono >= t) {
            return Reset::Working;
        }
        self.wait_until = None;
        let Some(layout) = Layout::of_len(self.detected) else {
            cx.say(
                TextSeverity::Warning,
                format_args!(
                    "vrpn_ADBox: trying to detect ad-box ({} bytes answered)",
                    self.detected
                ),
            );
            self.first = None;
            return Reset::Failed(Retry::After(RETRY_DELAY));
        };
        cx.say(
            TextSeverity::Normal,
            format_args!(
                "vrpn_ADBox: ad-box with {} digital and {} analog ports detected",
                layout.buttons(),
                layout.channels()
            ),
        );
        if self.layout != Some(layout) {
            self.layout = Some(layout);
            self.buttons.set_num_buttons(layout.buttons());
            self.analog.set_num_channels(layout.channels());
        }
        // The detection's answer is an answer.
        self.answer(layout, cx);
        if self.resync_until.is_none() {
            self.ask(cx);
        }
        Reset::Done
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.wait_until
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        let Some(layout) = self.layout else { return };
        for &b in bytes {
            if self.resync_until.is_some() {
                cx.skipped(1, "vrpn_ADBox", format_args!(" (an answer out of step)"));
                self.resync_until = Some(cx.now.mono + QUIET);
                continue;
            }
            if self.got == 0 {
                self.first = Some(cx.now);
            }
            if self.got < layout.len {
                self.answer[self.got] = b;
                self.got += 1;
                // C++ waits up to this long for each byte.
                self.wait_until = Some(cx.now.mono + REPLY_WAIT);
            }
            if self.got == layout.len {
                self.answer(layout, cx);
                if self.resync_until.is_none() {
                    self.ask(cx);
                }
            }
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.resync_until.is_some_and(|t| cx.now.mono >= t) {
            self.resync_until = None;
            self.ask(cx);
        } else if self.wait_until.is_some_and(|t| cx.now.mono >= t) {
            if self.got > 0 {
                cx.skipped(
                    self.got as u64,
                    "vrpn_ADBox",
                    format_args!(" (an answer cut short)"),
                );
            }
            self.ask(cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.resync_until.or(self.wait_until)
    }

    fn stopped(&mut self) {
        self.got = 0;
        self.first = None;
        self.wait_until = None;
        self.resync_until = None;
    }

    fn silent(&mut self, _last_record: Now, cx: &mut Cx<'_>) {
        cx.say(
            TextSeverity::Error,
            format_args!("vrpn_ADBox: no answer for 1 s, detecting the box again"),
        );
    }
}
