//! A Haydon Kerk IDEA stepper-motor drive on a serial line (C++ `vrpn_IDEA`): its `vrpn.cfg`
//! line ([`config`]), its answers ([`answer`]), its moves ([`moves`]), its reset ([`reset`]),
//! its [`Protocol`], and a simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_IDEA NAME PORT RUN START END ACCEL DECEL RUN_I HOLD_I ACCEL_I DECEL_I DELAY STEP
//!           HIGH_LIMIT LOW_LIMIT OUT1 OUT2 OUT3 OUT4 INITIAL_MOVE FRACTION RESET_LOCATION
//! ```
//!
//! 57600 baud 8N1 ([`config::BAUD`]), as C++ opens it. Speeds in steps/s, accelerations in
//! steps/s², currents in mA, the delay in ms; limits are inputs 1–4 (-1: none); outputs 0
//! (off), 1 (on) or -1 (left alone); the initial move and the reset location in steps.
//!
//! # What is served
//!
//! `NAME` is an Analog with one channel, the motor's position in steps (the drive counts in
//! 1/64 steps), an Analog_Output with one channel (a request to set it to `v` moves the motor
//! to the absolute position `v` steps), and a Button with four buttons, inputs 1–4. The
//! driver asks for the position (`l`) and the inputs (`:`) in turn, each as soon as the other
//! is answered, and reports what changed, stamped with the arrival of the answer's first
//! byte (the Analog RELIABLE, as C++). A move the motor makes is seen as it goes. A move
//! forward while the high limit switch is closed (or backward with the low one) is refused
//! with C++'s warning; a limit switch closing is warned of. A client whose remote pings the
//! device gets the position at once, as in C++.
//!
//! # Supervision
//!
//! An answer that does not come within [`REASK_AFTER`] is asked for again; 2 s without an
//! answer sends C++'s `Timeout, resetting...` text and resets the drive on the open port. A
//! port that fails is reopened every second.
//!
//! # Differences from C++ VRPN
//!
//! * No sleeps (C++ sleeps 350 ms in each reset and blocks the server for every move of the
//!   reset): the reset is a state machine of deadlines ([`reset`]).
//! * Garbage costs the bytes it spans, not a flush of the input; a lost answer is asked for
//!   again after [`REASK_AFTER`] (C++: after 1 s).
//! * A limit index above 4 is refused by the configuration (C++ reads past its four buttons).
//! * Moves asked for during a reset are made once it is done (the last one wins).

pub mod answer;
pub mod config;
pub mod moves;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::answer::{Answer, Framer};
use self::config::BAUD;
use self::moves::{write_move, Outcome};
use self::reset::{Progress, ResetSequence};
use crate::devices::analog_output::{AnalogOutputServer, OutputRequests};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::wire::class;
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::Idea;

/// The registry entry: `vrpn_IDEA`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_IDEA"],
    parse: config::parse,
    hints: &[],
};

/// Inputs reported as buttons.
pub const BUTTONS: usize = 4;
/// Time an answer has before it is asked for again.
pub const REASK_AFTER: Duration = Duration::from_millis(250);
/// Silence after which the drive is reset (C++'s time-out).
pub const TIMEOUT: Duration = Duration::from_secs(2);
/// Pause before another attempt after a failed reset.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);

/// The drive's protocol. See the module documentation.
pub struct IdeaProtocol {
    cfg: Idea,
    analog: AnalogServer,
    _output: AnalogOutputServer,
    buttons: ButtonServer,
    /// Moves asked for, not yet written (the last one wins), and pings of the Analog.
    requests: OutputRequests,
    reset: ResetSequence,
    framer: Framer,
    /// The last position read (1/64 steps) and input bits.
    position: i64,
    inputs: u8,
    /// The letter of the answer the last request asks for, and when it was written.
    expect: Option<u8>,
    asked_at: Option<Instant>,
    last_now: Option<Instant>,
}

impl IdeaProtocol {
    /// The protocol of a `vrpn_IDEA` entry, with its servers on `conn`.
    pub fn new(cfg: &Idea, conn: &Connection) -> Result<IdeaProtocol, Error> {
        let mut analog = AnalogServer::new(&cfg.name, conn, 1)?;
        analog.set_class_of_service(class::RELIABLE);
        let output = AnalogOutputServer::new(&cfg.name, conn, 1)?;
        let buttons = ButtonServer::new(&cfg.name, conn, BUTTONS)?;
        // The server half checks requests (and answers one for another channel with an
        // error text); this sees each one for channel 0 as it came.
        let requests = output.watch_requests(1, Some(analog.sender()))?;
        Ok(IdeaProtocol {
            cfg: cfg.clone(),
            analog,
            _output: output,
            buttons,
            requests,
            reset: ResetSequence::new(cfg),
            framer: Framer::new(),
            position: 0,
            inputs: 0,
            expect: None,
            asked_at: None,
            last_now: None,
        })
    }

    /// The position last read, in steps.
    pub fn position(&self) -> f64 {
        self.position as f64 / 64.0
    }

    /// Writes the request for `letter`'s answer (`l` or `:`).
    fn ask(&mut self, letter: u8, cx: &mut Cx<'_>) {
        cx.write(&[letter, b'\r']);
        self.expect = Some(letter);
        self.asked_at = Some(cx.now.mono);
    }

    /// One answer while streaming: report it, and ask for the other one when it is the answer
    /// waited for (an answer nobody waits for, a late one, starts no second chain).
    fn answer(&mut self, a: Answer, at: Now, cx: &mut Cx<'_>) {
        let (letter, next) = match a {
            Answer::Position(p) => {
                self.position = p;
                self.analog.set_channel(0, p as f64 / 64.0);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.analog.report_changes(Some(at.wall));
                (b'l', b':')
            }
            Answer::Io(bits) => {
                let before = self.inputs;
                self.inputs = (bits & 0xF) as u8;
                for i in 0..BUTTONS {
                    self.buttons.set_button(i, self.inputs & (1 << i) != 0);
                }
                let rose = |limit: Option<u8>| {
                    limit.is_some_and(|i| {
                        let bit = 1 << (i - 1);
                        self.inputs & bit != 0 && before & bit == 0
                    })
                };
                if rose(self.cfg.high_limit) {
                    cx.say(
                        TextSeverity::Warning,
                        format_args!("Encountered high limit"),
                    );
                }
                if rose(self.cfg.low_limit) {
                    cx.say(TextSeverity::Warning, format_args!("Encountered low limit"));
                }
                self.buttons.set_timestamp(at.wall);
                let _ = self.buttons.report_changes();
                (b':', b'l')
            }
            // Answers to nothing asked while streaming (a late reset answer).
            _ => return,
        };
        cx.record(at);
        if self.expect == Some(letter) {
            self.ask(next, cx);
        }
    }

    /// Writes the move asked for and answers a ping.
    fn send_requests(&mut self, cx: &mut Cx<'_>) {
        if self.requests.take_pinged() {
            let _ = self.analog.report(Some(cx.now.wall));
        }
        let Some((_, to)) = self.requests.take_next() else {
            return;
        };
        let from = self.position();
        let outcome = write_move(&self.cfg, from, self.inputs, to, 1.0, &mut |b| cx.write(b));
        if outcome == Outcome::IntoLimit {
            cx.say(
                TextSeverity::Warning,
                format_args!("vrpn_IDEA::send_move_request(): Asked to move into limit"),
            );
        }
    }

    fn reask_due(&self) -> Option<Instant> {
        self.asked_at.map(|t| t + REASK_AFTER)
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        if self.reset.take_into_limit() {
            cx.say(
                TextSeverity::Warning,
                format_args!("vrpn_IDEA::send_move_request(): Asked to move into limit"),
            );
        }
        match p {
            Progress::Working => Reset::Working,
            Progress::Done => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("reset complete (this is good)"),
                );
                self.position = self.reset.position();
                self.inputs = self.reset.inputs();
                // The reset's last command asked for the position.
                self.expect = Some(b'l');
                self.asked_at = Some(cx.now.mono);
                Reset::Done
            }
            Progress::Failed(f) => {
                cx.say(TextSeverity::Error, format_args!("{}", f.text()));
                Reset::Failed(Retry::After(RETRY_DELAY))
            }
        }
    }
}

impl Protocol for IdeaProtocol {
    const KIND: &'static str = "IDEA drive";

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
        self.expect = None;
        self.asked_at = None;
        self.reset.start(cx.now, cx.port());
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        for (i, &b) in bytes.iter().enumerate() {
            let Some((a, at)) = self.framer.push(b, cx.now) else {
                continue;
            };
            let p = self.reset.answer(a, at, cx.port());
            if p == Progress::Working {
                continue;
            }
            self.framer.take_skipped();
            let r = self.progress(p, cx);
            if r == Reset::Done {
                // Answers that came in the same read are answers, not part of the reset.
                self.received(&bytes[i + 1..], cx);
            }
            return r;
        }
        // Bytes before the drive answers (a reset's noise) are not reported.
        self.framer.take_skipped();
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        let p = self.reset.poll(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        for &b in bytes {
            if let Some((a, at)) = self.framer.push(b, cx.now) {
                self.answer(a, at, cx);
            }
            let skipped = self.framer.take_skipped();
            if skipped > 0 {
                cx.skipped(skipped, "IDEA", format_args!(""));
            }
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        self.send_requests(cx);
        if self.reask_due().is_some_and(|d| cx.now.mono >= d) {
            self.ask(b'l', cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        if self.requests.is_pending() {
            return self.last_now;
        }
        self.reask_due()
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
        self.expect = None;
        self.asked_at = None;
    }

    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        let (cur, ts) = (cx.now.wall, last_record.wall);
        cx.say(
            TextSeverity::Error,
            format_args!(
                "Timeout, resetting... current_time={}:{}, timestamp={}:{}",
                cur.sec, cur.usec, ts.sec, ts.usec
            ),
        );
    }
}
