//! An Atmel ATmega32 board (Albotronic, Bauhaus University Weimar) on a serial line (C++
//! `vrpn_Atmel`): its `vrpn.cfg` entry ([`config`]), its commands ([`command`]), its
//! [`Protocol`], and a simulator (`sim`, with the `sim` feature).
//!
//! # Configuration served
//!
//! ```text
//! vrpn_Atmel NAME PORT BAUD CHANNELS
//! vrpn_Atmel CHANNEL MODE
//! vrpn_Atmel -1 END
//! ```
//!
//! 8N1 at 38400 baud when `BAUD` is 38400, else at 9600 (as C++). Channel `i` is register `i`
//! of the board; its mode is `RW`, `RO`, `WO` or `NA` (the default).
//!
//! # What is served
//!
//! `NAME` is an Analog and an Analog_Output of `CHANNELS` channels. The driver goes round the
//! channels in **cycles**, as C++ does in each pass of its loop: a channel a client asked to
//! change is written (if it is `RW` or `WO` and the value is in 0..=255) and its echo awaited;
//! any other `RW`/`RO` channel is read. After each cycle every channel is reported, stamped
//! with the arrival of the first byte of the cycle's first answer. A channel reports C++'s
//! values: the register, the value written, `-1` when unused, or an error code
//! ([`command::reported`]).
//!
//! # Reset and supervision
//!
//! The reset reads every `RW`/`RO` register once; an unanswered read fails it, and it is
//! tried again after [`RETRY_DELAY`] (C++ marks that channel unused for good). Without a
//! register to read it waits up to [`CONNECT_WAIT`] for any byte from the board (C++ waits
//! this long before it starts). Each exchange waits [`REPLY_WAIT`] for its answer
//! (C++'s time-out); an unanswered read reports `-21`. [`ALIVE_WAIT`] without a byte from the
//! board resets it (C++ exits).

pub mod command;
pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::command::{address, reported, write_command, Awaited, Matcher, Mode, Step};
use crate::devices::analog_output::{AnalogOutputServer, OutputRequests};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, Connection, Error};

pub use self::config::Atmel;

/// The registry entry: `vrpn_Atmel`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Atmel"],
    parse: config::parse,
    hints: &[],
};

/// The wait for an exchange's answer (C++'s 150 ms).
pub const REPLY_WAIT: Duration = Duration::from_millis(150);
/// The reset's wait for a first byte from the board (C++'s 5 s).
pub const CONNECT_WAIT: Duration = Duration::from_secs(5);
/// Silence from the board after which it is reset (C++'s 3 s).
pub const ALIVE_WAIT: Duration = Duration::from_secs(3);
/// The pause between cycles that exchange nothing (no channel to read or write).
pub const IDLE_CYCLE: Duration = Duration::from_millis(10);
/// The pause before another reset after a failed one.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);

/// An exchange under way: the channel, what is awaited, until when.
#[derive(Clone, Copy, Debug)]
struct Exchange {
    channel: usize,
    matcher: Matcher,
    until: Instant,
}

/// How an exchange ended.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Outcome {
    Value(u16),
    Confirmed,
    Failed,
}

/// The board's protocol. See the module documentation.
pub struct AtmelProtocol {
    baud: u32,
    modes: Vec<Mode>,
    analog: AnalogServer,
    _output: AnalogOutputServer,
    /// Values clients asked for since the last cycle began.
    requests: OutputRequests,
    /// What each channel reports (C++'s `channel`).
    channel: Vec<f64>,
    /// What each channel should be (C++'s `o_channel`): a difference is a write.
    out: Vec<f64>,
    /// The next channel the cycle (or the reset's reads) looks at.
    next: usize,
    exchange: Option<Exchange>,
    /// The first byte of the cycle's first answer.
    first: Option<Now>,
    /// Whether the cycle exchanged anything.
    exchanged: bool,
    /// The reset's reads are running (else a cycle).
    initializing: bool,
    /// The reset's read of this channel was not answered.
    init_failed: Option<usize>,
    /// A byte came from the board since the reset began.
    heard: bool,
    /// The reset waits for a first byte until then.
    connect_by: Option<Instant>,
    /// The last byte from the board (or the end of the reset).
    last_byte: Option<Instant>,
    /// When the next cycle starts.
    next_cycle: Option<Instant>,
}

impl AtmelProtocol {
    /// The protocol of a `vrpn_Atmel` entry, with its servers on `conn`.
    pub fn new(cfg: &Atmel, conn: &Connection) -> Result<AtmelProtocol, Error> {
        let n = cfg.modes.len();
        let analog = AnalogServer::new(&cfg.name, conn, n)?;
        let output = AnalogOutputServer::new(&cfg.name, conn, n)?;
        // The server half checks each request (an error text for a channel out of range);
        // this keeps the values asked for until the next cycle writes them.
        let requests = output.watch_requests(n, None)?;
        Ok(AtmelProtocol {
            baud: cfg.line_speed(),
            modes: cfg.modes.clone(),
            analog,
            _output: output,
            requests,
            channel: vec![reported::NOT_VALID; n],
            out: vec![reported::NOT_VALID; n],
            next: 0,
            exchange: None,
            first: None,
            exchanged: false,
            initializing: false,
            init_failed: None,
            heard: false,
            connect_by: None,
            last_byte: None,
            next_cycle: None,
        })
    }

    /// What channel `i` reports now.
    pub fn channel(&self, i: usize) -> f64 {
        self.channel[i]
    }

    /// Starts a cycle: the values clients asked for become the ones to write.
    fn start_cycle(&mut self, cx: &mut Cx<'_>) {
        self.next_cycle = None;
        self.next = 0;
        self.first = None;
        self.exchanged = false;
        while let Some((c, v)) = self.requests.take_next() {
            self.out[c] = v;
        }
        self.step(cx);
    }

    /// Goes on from channel `next` until an exchange starts or the channels are done.
    fn step(&mut self, cx: &mut Cx<'_>) {
        while self.next < self.modes.len() {
            let c = self.next;
            self.next += 1;
            let mode = self.modes[c];
            if self.initializing {
                match address(c).filter(|_| mode.readable()) {
                    Some(a) => return self.ask(c, Awaited::Read(a), cx),
                    None => {
                        self.channel[c] = reported::NOT_VALID;
                        self.out[c] = reported::NOT_VALID;
                    }
                }
                continue;
            }
            let want = self.out[c];
            if want == reported::NOT_VALID {
                continue;
            }
            if want != self.channel[c] {
                if !mode.writable() {
                    self.channel[c] = reported::NOT_WRITABLE;
                    cx.say(
                        TextSeverity::Warning,
                        format_args!("vrpn_Atmel: channel {c} not writable"),
                    );
                } else if !(0.0..=255.0).contains(&want) {
                    self.channel[c] = reported::OUT_OF_RANGE;
                    cx.say(
                        TextSeverity::Warning,
                        format_args!("vrpn_Atmel: channel {c}: value {want} out of range"),
                    );
                } else if let Some(cmd) = write_command(c, want as u8) {
                    return self.ask(c, Awaited::Echo(cmd), cx);
                } else {
                    self.channel[c] = reported::WRITE_FAILED;
                }
                continue;
            }
            if mode.readable() {
                match address(c) {
                    Some(a) => return self.ask(c, Awaited::Read(a), cx),
                    None => self.channel[c] = reported::READ_FAILED,
                }
            }
        }
        self.cycle_done(cx);
    }

    /// Writes a request (after flushing what came before it, as C++ does).
    fn ask(&mut self, channel: usize, awaited: Awaited, cx: &mut Cx<'_>) {
        cx.flush_input();
        match awaited {
            Awaited::Read(a) => cx.write(&[a]),
            Awaited::Echo(cmd) => cx.write(&cmd),
        }
        self.exchanged = true;
        self.exchange = Some(Exchange {
            channel,
            matcher: Matcher::new(awaited),
            until: cx.now.mono + REPLY_WAIT,
        });
    }

    /// The exchange under way ended.
    fn finish(&mut self, outcome: Outcome, cx: &mut Cx<'_>) {
        let Some(ex) = self.exchange.take() else {
            return;
        };
        let c = ex.channel;
        if self.initializing && outcome == Outcome::Failed {
            // The reset failed; `reset_progress` says so.
            self.init_failed = Some(c);
            return;
        }
        self.channel[c] = match (outcome, ex.matcher.awaited()) {
            (Outcome::Value(v), _) => f64::from(v),
            (Outcome::Confirmed, _) => self.out[c],
            (Outcome::Failed, Awaited::Read(_)) => reported::READ_FAILED,
            (Outcome::Failed, Awaited::Echo(_)) => reported::WRITE_FAILED,
        };
        if self.initializing {
            self.out[c] = self.channel[c];
        }
        if outcome != Outcome::Failed {
            if let Some(at) = self.first {
                cx.record(at);
            }
        }
        self.step(cx);
    }

    /// The channels are done: report them.
    fn cycle_done(&mut self, cx: &mut Cx<'_>) {
        if self.initializing {
            // The reset ends in `reset_*` once a byte was heard.
            return;
        }
        self.out.copy_from_slice(&self.channel);
        self.report(cx);
        self.next_cycle = Some(if self.exchanged {
            cx.now.mono
        } else {
            cx.now.mono + IDLE_CYCLE
        });
    }

    fn report(&mut self, cx: &mut Cx<'_>) {
        let at = self.first.unwrap_or(cx.now);
        for (c, &v) in self.channel.iter().enumerate() {
            self.analog.set_channel(c, v);
        }
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.analog.report(Some(at.wall));
    }

    /// Bytes from the board, in the reset or a cycle.
    fn bytes(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        if !bytes.is_empty() {
            self.heard = true;
            self.last_byte = Some(cx.now.mono);
        }
        let mut skipped = 0u64;
        for (i, &b) in bytes.iter().enumerate() {
            let Some(ex) = self.exchange.as_mut() else {
                // Between exchanges: whatever the board sends of its own accord.
                continue;
            };
            let outcome = match ex.matcher.push(b) {
                Step::Skip => {
                    skipped += 1;
                    continue;
                }
                Step::Started => {
                    if self.first.is_none() {
                        self.first = Some(cx.now);
                    }
                    continue;
                }
                Step::Value(v) => Outcome::Value(v),
                Step::Confirmed => Outcome::Confirmed,
                Step::Failed => Outcome::Failed,
            };
            self.finish(outcome, cx);
            if self.exchange.is_some() {
                // The next request went out after these bytes came: C++ flushes them.
                skipped += (bytes.len() - i - 1) as u64;
                break;
            }
        }
        if skipped > 0 {
            cx.skipped(skipped, "vrpn_Atmel", format_args!(""));
        }
    }

    fn timed_out(&self, now: Instant) -> bool {
        self.exchange.is_some_and(|ex| now >= ex.until)
    }
}

impl Protocol for AtmelProtocol {
    const KIND: &'static str = "vrpn_Atmel";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        // Liveness is the board's bytes, watched in `poll` (an unanswered read is reported,
        // not a failure).
        Supervision {
            watchdog: None,
            on_silence: Recovery::Reset,
            pause: None,
            skip_note_interval: Duration::from_secs(1),
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.stopped();
        self.initializing = true;
        self.heard = false;
        self.connect_by = Some(cx.now.mono + CONNECT_WAIT);
        cx.flush_input();
        self.step(cx);
        self.reset_progress(cx)
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.bytes(bytes, cx);
        self.reset_progress(cx)
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.timed_out(cx.now.mono) {
            self.finish(Outcome::Failed, cx);
        }
        if self.exchange.is_none()
            && !self.heard
            && self.connect_by.is_some_and(|t| cx.now.mono >= t)
        {
            return self.reset_failed(None, cx);
        }
        self.reset_progress(cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        match self.exchange {
            Some(ex) => Some(ex.until),
            None => self.connect_by,
        }
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.bytes(bytes, cx);
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        let now = cx.now.mono;
        if self.last_byte.is_some_and(|t| now >= t + ALIVE_WAIT) {
            cx.say(
                TextSeverity::Error,
                format_args!(
                    "vrpn_Atmel: connection timed out after {} s without a byte from the board; \
                     starting it again",
                    ALIVE_WAIT.as_secs()
                ),
            );
            cx.reset();
            return;
        }
        if self.timed_out(now) {
            self.finish(Outcome::Failed, cx);
        }
        if self.exchange.is_none() && self.next_cycle.is_some_and(|t| now >= t) {
            self.start_cycle(cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        let alive = self.last_byte.map(|t| t + ALIVE_WAIT);
        let work = match self.exchange {
            Some(ex) => Some(ex.until),
            None => self.next_cycle,
        };
        alive.into_iter().chain(work).min()
    }

    fn stopped(&mut self) {
        self.exchange = None;
        self.next_cycle = None;
        self.next = 0;
        self.first = None;
        self.initializing = false;
        self.init_failed = None;
        self.connect_by = None;
        self.last_byte = None;
    }
}

impl AtmelProtocol {
    /// Whether the reset is done: its reads are over and the board has sent a byte.
    fn reset_progress(&mut self, cx: &mut Cx<'_>) -> Reset {
        if let Some(c) = self.init_failed.take() {
            return self.reset_failed(Some(c), cx);
        }
        if self.exchange.is_some() || !self.heard {
            return Reset::Working;
        }
        self.initializing = false;
        self.connect_by = None;
        cx.say(
            TextSeverity::Normal,
            format_args!("vrpn_Atmel: Atmel started"),
        );
        self.report(cx);
        self.last_byte = Some(cx.now.mono);
        self.next_cycle = Some(cx.now.mono);
        Reset::Done
    }

    /// The reset failed: nothing came from the board, or the read of `channel` was not
    /// answered.
    fn reset_failed(&mut self, channel: Option<usize>, cx: &mut Cx<'_>) -> Reset {
        match channel {
            Some(c) if self.heard => cx.say(
                TextSeverity::Error,
                format_args!("vrpn_Atmel: no answer reading register {c}; trying again"),
            ),
            _ => cx.say(
                TextSeverity::Error,
                format_args!(
                    "vrpn_Atmel: Atmel not connected to the specified port. Connect and try \
                     again."
                ),
            ),
        }
        self.stopped();
        Reset::Failed(Retry::After(RETRY_DELAY))
    }
}
