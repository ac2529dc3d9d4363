//! A Tektronix 4662 plotter on a serial line as a Poser and a Tracker (C++
//! `vrpn_Poser_Tek4662`): its `vrpn.cfg` line ([`config`]), its bytes ([`gin`]), its
//! [`Protocol`], and a simulated plotter (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tek4662 NAME PORT BAUD
//! ```
//!
//! 8N1 at `BAUD` (the plotter's usual rate is 1200).
//!
//! # What is served
//!
//! `NAME` is a Poser and a Tracker (one sensor). A client's pose request is clamped to the
//! workspace (x 0–0.381 m, y 0–0.254 m, z 0; the orientation is ignored) and the pen is sent
//! there: a move command, then a position request (GIN). The plotter answers GIN requests
//! only once the move before them is done. Each answer is reported as a Tracker pose of
//! sensor 0: (x, y, 0) in metres, identity orientation, stamped with the arrival of the
//! answer's first byte. Between moves the position is asked for 250 ms after the last
//! answer began, so a pen moved by the plotter's joystick is followed about four times a
//! second. Requests that come while an answer is awaited wait for it; of several, the last
//! is carried out (C++ behaves the same). Velocity and relative requests have no effect, as
//! in C++.
//!
//! # Reset and supervision
//!
//! The reset writes 17 NULs, `ESC A E` (plotter on), `ESC A N` (reset) and a GIN request;
//! its answer (within [`RESET_WAIT`]) is the first report. [`TIMEOUT`] without an answer sends
//! C++'s `Device timeout (resetting)` text and resets the plotter on the open port. A request
//! unanswered for [`ASK_AGAIN_AFTER`] while the line is quiet (an answer garbled on the line)
//! is asked again.

pub mod config;
pub mod gin;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use self::gin::{clamp_to_workspace, counts, metres, move_command, Framer, Gin, GIN};
use crate::devices::poser::PoserIds;
use crate::devices::text::TextSeverity;
use crate::devices::tracker::TrackerServer;
use crate::dispatch::SenderFilter;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::wire::payload::poser::PoseRequest;
use crate::{Connection, Error};

pub use self::config::Tek4662;

/// The registry entry: `vrpn_Tek4662`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tek4662"],
    parse: config::parse,
    hints: &[],
};

/// The wait for the reset's answer (C++ waits this long).
pub const RESET_WAIT: Duration = Duration::from_secs(1);
/// Pause before another reset attempt (C++ sleeps this long before each attempt).
pub const RETRY_DELAY: Duration = Duration::from_millis(100);
/// Between moves, the position is asked for this long after the last answer began.
pub const POLL_INTERVAL: Duration = Duration::from_millis(250);
/// Silence after which the plotter is reset (C++'s watchdog).
pub const TIMEOUT: Duration = Duration::from_secs(5);
/// A request unanswered this long after the last byte heard or written is asked again. A
/// move across the whole workspace takes under a second at the plotter's 570 mm/s.
pub const ASK_AGAIN_AFTER: Duration = Duration::from_secs(2);

/// What clients asked for, not yet carried out.
#[derive(Default)]
struct Requests {
    /// Where the pen is to go (clamped to the workspace).
    target: Option<[f64; 3]>,
    /// Requests refused since the last text about them (a coordinate not a number).
    refused: u32,
}

/// The plotter's protocol. See the module documentation.
pub struct Tek4662Protocol {
    baud: u32,
    tracker: TrackerServer,
    requests: Rc<RefCell<Requests>>,
    framer: Framer,
    /// GIN requests written and not answered yet.
    outstanding: u32,
    /// The first byte of the last answer (or the end of the reset): the poll counts from it.
    last_answer: Option<Instant>,
    /// The last byte heard or request written: an unanswered request is asked again
    /// [`ASK_AGAIN_AFTER`] later.
    last_activity: Option<Instant>,
    /// The reset's deadline and the bytes heard during the attempt.
    answer_by: Option<Instant>,
    reset_heard: usize,
    last_now: Option<Instant>,
}

impl Tek4662Protocol {
    /// The protocol of a `vrpn_Tek4662` entry, with its Tracker and Poser on `conn`.
    pub fn new(cfg: &Tek4662, conn: &Connection) -> Result<Tek4662Protocol, Error> {
        let tracker = TrackerServer::new(&cfg.name, conn, 1)?;
        let requests: Rc<RefCell<Requests>> = Rc::default();
        // The Poser shares the Tracker's name, hence its sender.
        let ids = PoserIds::register(conn)?;
        let r = requests.clone();
        conn.register_handler(ids.pose, SenderFilter::Only(tracker.sender()), move |m| {
            // A request of the wrong length is ignored (C++ ignores it too).
            if let Ok(req) = PoseRequest::decode(m.payload) {
                let mut r = r.borrow_mut();
                match clamp_to_workspace(req.pos) {
                    Some(p) => r.target = Some(p),
                    None => r.refused += 1,
                }
            }
        });
        Ok(Tek4662Protocol {
            baud: cfg.baud,
            tracker,
            requests,
            framer: Framer::new(),
            outstanding: 0,
            last_answer: None,
            last_activity: None,
            answer_by: None,
            reset_heard: 0,
            last_now: None,
        })
    }

    /// GIN requests written and not answered yet (for tests).
    pub fn outstanding(&self) -> u32 {
        self.outstanding
    }

    /// Reports an answer whose first byte arrived at `at`.
    fn report(&mut self, gin: Gin, at: Now, cx: &mut Cx<'_>) {
        cx.record(at);
        self.last_answer = Some(at.mono);
        let pos = [metres(gin.x), metres(gin.y), 0.0];
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self
            .tracker
            .report_pose(0, at.wall, pos, [0.0, 0.0, 0.0, 1.0]);
    }

    /// Writes a position request.
    fn ask(&mut self, cx: &mut Cx<'_>) {
        cx.write(&GIN);
        self.outstanding += 1;
        self.last_activity = Some(cx.now.mono);
    }

    /// When the next request is due: at once for a move, [`POLL_INTERVAL`] after the last
    /// answer otherwise, or, while one is awaited, [`ASK_AGAIN_AFTER`] after the last byte.
    fn due(&self) -> Option<Instant> {
        if self.outstanding > 0 {
            return self.last_activity.map(|t| t + ASK_AGAIN_AFTER);
        }
        let r = self.requests.borrow();
        if r.target.is_some() || r.refused > 0 {
            return self.last_now;
        }
        self.last_answer.map(|t| t + POLL_INTERVAL)
    }
}

impl Protocol for Tek4662Protocol {
    const KIND: &'static str = "Tek4662 plotter";

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
        self.last_now = Some(cx.now.mono);
        self.framer.clear();
        self.outstanding = 0;
        self.reset_heard = 0;
        cx.flush_input();
        cx.write(&gin::RESET_SEQUENCE);
        self.answer_by = Some(cx.now.mono + RESET_WAIT);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        self.reset_heard += bytes.len();
        for (i, &b) in bytes.iter().enumerate() {
            if let Some((gin, at)) = self.framer.push(b, cx.now) {
                self.answer_by = None;
                self.framer.take_skipped();
                cx.say(
                    TextSeverity::Normal,
                    format_args!("vrpn_Poser_Tek4662: Reset correctly"),
                );
                self.report(gin, at, cx);
                // Answers that came in the same read are answers, not part of the reset.
                self.received(&bytes[i + 1..], cx);
                return Reset::Done;
            }
        }
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        if self.answer_by.is_some_and(|t| cx.now.mono >= t) {
            self.answer_by = None;
            if self.reset_heard < gin::ANSWER_LEN {
                cx.say(
                    TextSeverity::Error,
                    format_args!(
                        "vrpn_Poser_Tek4662::reset(): Expected {} characters, got {}",
                        gin::ANSWER_LEN,
                        self.reset_heard
                    ),
                );
            } else {
                cx.say(
                    TextSeverity::Error,
                    format_args!("vrpn_Poser_Tek4662: Error resetting"),
                );
            }
            return Reset::Failed(Retry::After(RETRY_DELAY));
        }
        Reset::Working
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.answer_by
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        if !bytes.is_empty() {
            self.last_activity = Some(cx.now.mono);
        }
        for &b in bytes {
            if let Some((gin, at)) = self.framer.push(b, cx.now) {
                self.outstanding = self.outstanding.saturating_sub(1);
                self.report(gin, at, cx);
            }
            let skipped = self.framer.take_skipped();
            if skipped > 0 {
                cx.skipped(skipped, "Tek4662", format_args!(""));
            }
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        let refused = std::mem::take(&mut self.requests.borrow_mut().refused);
        if refused > 0 {
            cx.say(
                TextSeverity::Warning,
                format_args!(
                    "vrpn_Poser_Tek4662: ignored {refused} pose request(s) with a coordinate \
                     that is not a number"
                ),
            );
        }
        if self.outstanding > 0 {
            if self
                .last_activity
                .is_some_and(|t| cx.now.mono < t + ASK_AGAIN_AFTER)
            {
                return;
            }
            // The answer was lost on the line: ask again.
            self.outstanding = 0;
            self.framer.clear();
        }
        let target = self.requests.borrow_mut().target.take();
        if let Some([x, y, _]) = target {
            cx.write(&move_command(counts(x), counts(y)));
            self.ask(cx);
        } else if self
            .last_answer
            .map_or(true, |t| cx.now.mono >= t + POLL_INTERVAL)
        {
            self.ask(cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.due()
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.outstanding = 0;
        self.answer_by = None;
        self.last_answer = None;
        self.last_activity = None;
    }

    fn silent(&mut self, _last_record: Now, cx: &mut Cx<'_>) {
        cx.say(
            TextSeverity::Error,
            format_args!("vrpn_Poser_Tek4662: Device timeout (resetting)"),
        );
    }
}
