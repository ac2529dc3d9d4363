//! One device lifecycle shared by every driver: the port opens, the device is reset (a
//! sequence of steps over deadlines, never a sleep), records stream, a silent device is caught
//! by a watchdog and reset again, a port that fails is reopened when it comes back.
//!
//! A driver supplies only its [`Protocol`]: the bytes of its reset steps and what answers
//! them, and how records are found and decoded. [`Lifecycle`] runs it:
//!
//! ```text
//!            port opened                    Reset::Done
//!  Closed ─────────────────▶ Resetting ──────────────────▶ Streaming
//!    ▲                        │    ▲                          │
//!    │     Retry::Reopen      │    │ Retry::Now / After(d)    │ silent for the watchdog:
//!    └────────────────────────┘    └── Retrying ◀─────────────┘ Recovery::Reset or Reopen
//! ```
//!
//! The lifecycle owns what every driver used to repeat: the mode, the watchdog (from the first
//! byte of the last good record, or the end of the reset), the failure texts, counting
//! records, resets and failures, the pause after repeated failures, rate-limited notes about
//! skipped bytes, and the text messages' stack buffer (no allocation while streaming). The
//! port itself — opening, reading with the poll's wake time, reporting a port that fails and
//! reopening it — is the serial layer's ([`SerialDevice`](crate::serial::SerialDevice)), the
//! same for every driver.
//!
//! **A reset never invents data.** The lifecycle sends no reports of its own, and a protocol
//! must not either when it is reset or stopped: the values a client holds stay as they are
//! until the device's first real record after the reset says otherwise. (Zeroing channels or
//! releasing buttons at a reset would show a client values the device never sent.)

use std::fmt;
use std::time::{Duration, Instant};

use super::text::with_text;
use crate::connection::Connection;
use crate::devices::text::TextSeverity;
use crate::dispatch::SenderId;
use crate::serial::{PortKind, PortOps, SerialDriver};
use crate::time::Now;

/// What a reset step led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reset {
    /// The reset goes on (waiting for an answer or a deadline).
    Working,
    /// The device is ready: records are expected from now on.
    Done,
    /// This attempt failed (the protocol has said why in a text); try again as given.
    Failed(Retry),
}

/// When to try again after a failed reset attempt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Retry {
    /// At once.
    Now,
    /// After a pause.
    After(Duration),
    /// Close the port, open it again, and start over.
    Reopen,
}

/// What the watchdog does to a device that went silent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recovery {
    /// Close and reopen the port, then reset the device.
    Reopen,
    /// Reset the device on the open port.
    Reset,
}

/// A pause after repeated failures, so that a dead device is not hammered with resets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pause {
    /// Every this many failures in a row (failed resets and watchdog time-outs; a good record
    /// sets the count back to 0)…
    pub every: u32,
    /// …the lifecycle sends `advice` (an error text) and waits this long before reopening.
    pub wait: Duration,
    /// What to check.
    pub advice: &'static str,
}

/// How a device is watched. Every field has a sensible default ([`Supervision::TRACKER`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Supervision {
    /// Longest silence (from the first byte of the last good record, or the end of the reset)
    /// before the device is declared failed; `None` where silence is normal (a joystick no
    /// one touches).
    pub watchdog: Option<Duration>,
    /// What the watchdog does.
    pub on_silence: Recovery,
    /// The pause after repeated failures, if any.
    pub pause: Option<Pause>,
    /// At most one note about skipped bytes per this interval.
    pub skip_note_interval: Duration,
}

impl Supervision {
    /// A streaming tracker, as C++ VRPN watches one: 2 s of silence reopens the port and
    /// resets the device; no pause.
    pub const TRACKER: Supervision = Supervision {
        watchdog: Some(Duration::from_secs(2)),
        on_silence: Recovery::Reopen,
        pause: None,
        skip_note_interval: Duration::from_secs(1),
    };

    /// A device that sends only when something changes: no watchdog.
    pub const QUIET: Supervision = Supervision {
        watchdog: None,
        on_silence: Recovery::Reset,
        pause: None,
        skip_note_interval: Duration::from_secs(1),
    };
}

impl Default for Supervision {
    fn default() -> Supervision {
        Supervision::TRACKER
    }
}

/// A device's protocol: everything a driver writes. The [`Lifecycle`] calls it; `cx` carries
/// out what it asks (writes, flushes, texts) and learns of good records through
/// [`Cx::record`].
///
/// The reset is a state machine over deadlines: [`start_reset`](Self::start_reset) writes the
/// first step and returns; answers come to [`reset_received`](Self::reset_received), deadlines
/// to [`reset_poll`](Self::reset_poll) at [`reset_deadline`](Self::reset_deadline). Once it
/// returns [`Reset::Done`], bytes go to [`received`](Self::received), which finds records
/// byte by byte (a read may hold part of a record, several, or garbage), reports each, and
/// calls [`Cx::record`] with the arrival time of its first byte.
pub trait Protocol {
    /// What the device is, for the lifecycle's texts (`"DynaSight"`).
    const KIND: &'static str;

    /// How to open the port.
    fn port_kind(&self) -> PortKind;

    /// How the device is watched ([`Supervision::TRACKER`] unless overridden).
    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    /// Starts a reset attempt: the port just opened, a previous attempt failed, or the device
    /// is reset again. Writes the first step.
    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset;

    /// Bytes arrived during the reset (`cx.now` is when the poll woke for the first of them).
    /// Bytes after the answer that ends the reset are dropped unless the protocol uses them
    /// (it may decode them as records before returning [`Reset::Done`]).
    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset;

    /// The reset's deadline passed.
    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset;

    /// When the reset next needs [`reset_poll`](Self::reset_poll).
    fn reset_deadline(&self) -> Option<Instant>;

    /// Bytes arrived while streaming (`cx.now` is when the poll woke for the first of them):
    /// find records, report them, and call [`Cx::record`] for each good one.
    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>);

    /// Time-driven work while streaming (a polled device's repeated request, an idle probe),
    /// at [`deadline`](Self::deadline).
    fn poll(&mut self, _cx: &mut Cx<'_>) {}

    /// When [`poll`](Self::poll) is next needed while streaming.
    fn deadline(&self) -> Option<Instant> {
        None
    }

    /// The port closed, or the device is about to be reset: forget partial records and
    /// the reset's progress. Must not report anything (a reset never invents data).
    fn stopped(&mut self) {}

    /// The port failed or vanished (the serial layer has reported it and reopens it when it
    /// comes back): a device whose C++ driver says something of its own says it here. Writes
    /// go nowhere.
    fn lost(&mut self, _cx: &mut Cx<'_>) {}

    /// The watchdog fired: say so. By default, C++ VRPN's two tracker texts.
    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        let (cur, ts) = (cx.now.wall, last_record.wall);
        cx.say(
            TextSeverity::Error,
            format_args!(
                "Tracker failed to read... current_time={}:{}, timestamp={}:{}",
                cur.sec, cur.usec, ts.sec, ts.usec
            ),
        );
        cx.say(
            TextSeverity::Error,
            format_args!(
                "Tracker failed, trying to reset (Try power cycle if more than 4 attempts made)"
            ),
        );
    }
}

/// Counts kept by the lifecycle, for tests and diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Good records (calls to [`Cx::record`]).
    pub records: u64,
    /// Reset attempts started.
    pub reset_attempts: u64,
    /// Resets that completed.
    pub resets: u64,
    /// Times the watchdog fired.
    pub watchdog_fired: u64,
    /// Failures since the last good record (failed resets and watchdog time-outs).
    pub failures_in_a_row: u32,
    /// Bytes the protocol skipped looking for records (through [`Cx::skipped`]).
    pub skipped_bytes: u64,
    /// Times the port was opened.
    pub opens: u64,
}

/// Where the lifecycle is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The port is closed (or being reopened).
    Closed,
    /// A reset attempt runs.
    Resetting,
    /// Waiting before the next reset attempt.
    Retrying {
        /// When it starts.
        at: Instant,
    },
    /// Records are expected.
    Streaming,
    /// Waiting after repeated failures before reopening the port.
    Pausing {
        /// When the port is reopened.
        until: Instant,
    },
}

/// What the protocol asked for during a call, carried out after it returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Request {
    #[default]
    None,
    Reset,
    Reopen,
}

/// Where a device's text messages go: its sender on the server connection.
pub struct Texts {
    conn: Connection,
    sender: Option<SenderId>,
}

impl Texts {
    /// Sends a VRPN text message from the device, formatted on the stack (no allocation).
    pub fn say(&self, severity: TextSeverity, args: fmt::Arguments<'_>) {
        if let Some(sender) = self.sender {
            // A failed send is the connection's business (it reports and drops the peer).
            with_text(args, |text| {
                let _ = self.conn.send_text(sender, severity, 0, text);
            });
        }
    }
}

/// Skipped bytes not reported yet, and when the last note went out.
#[derive(Clone, Copy, Debug, Default)]
struct SkipNotes {
    unreported: u64,
    last_note: Option<Instant>,
}

/// What a [`Protocol`] call works with: the time, the port's requests, the device's texts,
/// and the lifecycle's bookkeeping.
pub struct Cx<'a> {
    /// The time of the call: for bytes, when the poll woke for the first of them (the
    /// first-byte stamp of any record starting in them); for deadlines, the pass's time.
    pub now: Now,
    port: &'a mut PortOps,
    texts: &'a Texts,
    stats: &'a mut Stats,
    last_record: &'a mut Option<Now>,
    skips: &'a mut SkipNotes,
    skip_interval: Duration,
    request: &'a mut Request,
}

impl Cx<'_> {
    /// Writes `bytes` to the port.
    pub fn write(&mut self, bytes: &[u8]) {
        self.port.write(bytes);
    }

    /// Discards received, unread input.
    pub fn flush_input(&mut self) {
        self.port.flush_input();
    }

    /// Discards written, unsent output.
    pub fn flush_output(&mut self) {
        self.port.flush_output();
    }

    /// Sets the RTS line (harmlessly ignored where there is none, as on a pseudo-terminal).
    pub fn set_rts(&mut self, on: bool) {
        self.port.set_rts(on);
    }

    /// Sets the DTR line (as [`set_rts`](Self::set_rts)).
    pub fn set_dtr(&mut self, on: bool) {
        self.port.set_dtr(on);
    }

    /// Changes the line's speed on the open port, once everything written before has been
    /// handed to it (for a device told to switch its own rate; the port opens again at
    /// [`Protocol::port_kind`]'s rate).
    pub fn set_baud(&mut self, baud: u32) {
        self.port.set_baud(baud);
    }

    /// The port's requests so far in this call (for protocols built from parts that take
    /// [`PortOps`]).
    pub fn port(&mut self) -> &mut PortOps {
        self.port
    }

    /// The port and the device's texts at once, for a part (a reset state machine) that
    /// writes and speaks in the same call.
    pub fn port_and_texts(&mut self) -> (&mut PortOps, &Texts) {
        (self.port, self.texts)
    }

    /// Sends a VRPN text message from the device, formatted on the stack (no allocation):
    /// `cx.say(TextSeverity::Warning, format_args!("got {n} bytes"))`.
    pub fn say(&self, severity: TextSeverity, args: fmt::Arguments<'_>) {
        self.texts.say(severity, args);
    }

    /// A good record whose first byte arrived at `first_byte` was reported: feeds the
    /// watchdog, counts it, and clears the failure count.
    pub fn record(&mut self, first_byte: Now) {
        self.stats.records += 1;
        self.stats.failures_in_a_row = 0;
        *self.last_record = Some(first_byte);
    }

    /// `n` bytes were skipped looking for a record. A warning text says so at most once per
    /// [`Supervision::skip_note_interval`] (`KIND: skipped N bytes to find the next record`
    /// followed by `detail`, if not empty); bytes skipped in between are added to the next.
    pub fn skipped(&mut self, n: u64, kind: &str, detail: fmt::Arguments<'_>) {
        if n == 0 {
            return;
        }
        self.stats.skipped_bytes += n;
        self.skips.unreported += n;
        let now = self.now.mono;
        if self
            .skips
            .last_note
            .is_some_and(|t| now < t + self.skip_interval)
        {
            return;
        }
        let total = std::mem::take(&mut self.skips.unreported);
        self.skips.last_note = Some(now);
        self.texts.say(
            TextSeverity::Warning,
            format_args!("{kind}: skipped {total} bytes to find the next record{detail}"),
        );
    }

    /// Asks for a reset on the open port once this call returns (a device that said it is in
    /// the wrong mode, an unanswered probe).
    pub fn reset(&mut self) {
        if *self.request == Request::None {
            *self.request = Request::Reset;
        }
    }

    /// Asks for the port to be closed and reopened, then the device reset, once this call
    /// returns.
    pub fn reopen(&mut self) {
        *self.request = Request::Reopen;
    }

    /// The first byte of the last good record (or the end of the reset), if any since the
    /// port opened.
    pub fn last_record(&self) -> Option<Now> {
        *self.last_record
    }
}

/// A [`Protocol`] run through the shared lifecycle: the [`SerialDriver`] the serial layer (or
/// a simulated line in tests) runs. See the module documentation.
pub struct Lifecycle<P: Protocol> {
    name: String,
    protocol: P,
    texts: Texts,
    supervision: Supervision,
    phase: Phase,
    last_record: Option<Now>,
    stats: Stats,
    skips: SkipNotes,
    request: Request,
    /// Requests made while no port is open (in [`Protocol::lost`]), dropped.
    nowhere: PortOps,
}

impl<P: Protocol> Lifecycle<P> {
    /// Runs `protocol` for the device `name`, whose texts go out on `conn`.
    pub fn new(name: &str, protocol: P, conn: &Connection) -> Lifecycle<P> {
        Lifecycle {
            name: name.to_owned(),
            supervision: protocol.supervision(),
            protocol,
            texts: Texts {
                conn: conn.clone(),
                sender: conn.register_sender(name).ok(),
            },
            phase: Phase::Closed,
            last_record: None,
            stats: Stats::default(),
            skips: SkipNotes::default(),
            request: Request::None,
            nowhere: PortOps::new(),
        }
    }

    /// The protocol.
    pub fn protocol(&self) -> &P {
        &self.protocol
    }

    /// The protocol, to change it (tests).
    pub fn protocol_mut(&mut self) -> &mut P {
        &mut self.protocol
    }

    /// Where the lifecycle is.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// True once a reset completed and records are expected.
    pub fn is_streaming(&self) -> bool {
        self.phase == Phase::Streaming
    }

    /// The counts so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Runs `f` on the protocol with a context, then carries out what it asked for.
    fn call<R>(
        &mut self,
        now: Now,
        port: &mut PortOps,
        f: impl FnOnce(&mut P, &mut Cx<'_>) -> R,
    ) -> R {
        let mut cx = Cx {
            now,
            port,
            texts: &self.texts,
            stats: &mut self.stats,
            last_record: &mut self.last_record,
            skips: &mut self.skips,
            skip_interval: self.supervision.skip_note_interval,
            request: &mut self.request,
        };
        f(&mut self.protocol, &mut cx)
    }

    /// Carries out a reset or reopen the protocol asked for.
    fn follow_request(&mut self, now: Now, port: &mut PortOps) {
        match std::mem::take(&mut self.request) {
            Request::None => {}
            Request::Reset => self.start_reset(now, port),
            Request::Reopen => self.reopen(port),
        }
    }

    fn start_reset(&mut self, now: Now, port: &mut PortOps) {
        self.protocol.stopped();
        self.last_record = None;
        self.phase = Phase::Resetting;
        self.stats.reset_attempts += 1;
        let r = self.call(now, port, |p, cx| p.start_reset(cx));
        self.progress(r, now, port);
    }

    fn reopen(&mut self, port: &mut PortOps) {
        self.protocol.stopped();
        self.last_record = None;
        self.phase = Phase::Closed;
        port.reopen();
    }

    /// A failure: counted, and a pause after too many in a row. True when pausing.
    fn failed(&mut self, now: Now) -> bool {
        self.stats.failures_in_a_row += 1;
        let Some(pause) = self.supervision.pause else {
            return false;
        };
        if pause.every == 0 || self.stats.failures_in_a_row % pause.every != 0 {
            return false;
        }
        self.texts
            .say(TextSeverity::Error, format_args!("{}", pause.advice));
        self.protocol.stopped();
        self.last_record = None;
        self.phase = Phase::Pausing {
            until: now.mono + pause.wait,
        };
        true
    }

    fn progress(&mut self, r: Reset, now: Now, port: &mut PortOps) {
        if self.request != Request::None {
            self.follow_request(now, port);
            return;
        }
        match r {
            Reset::Working => {}
            Reset::Done => {
                self.phase = Phase::Streaming;
                self.stats.resets += 1;
                // The watchdog counts from the end of the reset, or from a record the
                // protocol already reported in the answer's read.
                if self.last_record.map_or(true, |t| t.mono < now.mono) {
                    self.last_record = Some(now);
                }
            }
            Reset::Failed(retry) => {
                if self.failed(now) {
                    return;
                }
                match retry {
                    Retry::Now => self.start_reset(now, port),
                    Retry::After(d) => {
                        self.protocol.stopped();
                        self.phase = Phase::Retrying { at: now.mono + d };
                    }
                    Retry::Reopen => self.reopen(port),
                }
            }
        }
    }

    fn watchdog(&mut self, now: Now, port: &mut PortOps) -> bool {
        let (Some(limit), Some(last)) = (self.supervision.watchdog, self.last_record) else {
            return false;
        };
        if now.mono < last.mono + limit {
            return false;
        }
        self.stats.watchdog_fired += 1;
        self.call(now, port, |p, cx| p.silent(last, cx));
        self.request = Request::None;
        if self.failed(now) {
            return true;
        }
        match self.supervision.on_silence {
            Recovery::Reopen => self.reopen(port),
            Recovery::Reset => self.start_reset(now, port),
        }
        true
    }
}

impl<P: Protocol> SerialDriver for Lifecycle<P> {
    fn name(&self) -> &str {
        &self.name
    }

    fn port_kind(&self) -> PortKind {
        self.protocol.port_kind()
    }

    fn opened(&mut self, now: Now, port: &mut PortOps) {
        self.stats.opens += 1;
        self.start_reset(now, port);
    }

    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        match self.phase {
            Phase::Closed | Phase::Retrying { .. } | Phase::Pausing { .. } => {}
            Phase::Resetting => {
                let r = self.call(arrived, port, |p, cx| p.reset_received(bytes, cx));
                self.progress(r, arrived, port);
            }
            Phase::Streaming => {
                self.call(arrived, port, |p, cx| p.received(bytes, cx));
                self.follow_request(arrived, port);
            }
        }
    }

    fn poll(&mut self, now: Now, port: &mut PortOps) {
        match self.phase {
            Phase::Closed => {}
            Phase::Resetting => {
                if self
                    .protocol
                    .reset_deadline()
                    .is_some_and(|d| now.mono >= d)
                {
                    let r = self.call(now, port, |p, cx| p.reset_poll(cx));
                    self.progress(r, now, port);
                }
            }
            Phase::Retrying { at } => {
                if now.mono >= at {
                    self.start_reset(now, port);
                }
            }
            Phase::Streaming => {
                if self.watchdog(now, port) {
                    return;
                }
                if self.protocol.deadline().is_some_and(|d| now.mono >= d) {
                    self.call(now, port, |p, cx| p.poll(cx));
                    self.follow_request(now, port);
                }
            }
            Phase::Pausing { until } => {
                if now.mono >= until {
                    self.reopen(port);
                }
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        match self.phase {
            Phase::Closed => None,
            Phase::Resetting => self.protocol.reset_deadline(),
            Phase::Retrying { at } => Some(at),
            Phase::Streaming => {
                let watchdog = self
                    .supervision
                    .watchdog
                    .zip(self.last_record)
                    .map(|(d, t)| t.mono + d);
                watchdog.into_iter().chain(self.protocol.deadline()).min()
            }
            Phase::Pausing { until } => Some(until),
        }
    }

    fn closed(&mut self, now: Now) {
        self.phase = Phase::Closed;
        self.protocol.stopped();
        self.last_record = None;
        let mut nowhere = std::mem::take(&mut self.nowhere);
        self.call(now, &mut nowhere, |p, cx| p.lost(cx));
        nowhere.clear();
        self.nowhere = nowhere;
        self.request = Request::None;
    }
}
