//! The reset and initialisation sequence, as a state machine over deadlines.
//!
//! Attempt `n` (counting consecutive attempts; a good status answer starts the count again)
//! sends, as C++ VRPN does:
//!
//! 1. the escalating break bytes: CR when n > 1 (leave a query loop), `Y` when n > 5 (tracking
//!    rather than point mode), `t` when n > 4 (toggle extended mode), Ctrl-Y when n > 2
//!    (reinitialise the tracker), each followed by [`BREAK_GAP`];
//! 2. `c` (stop continuous output), then waits until the line has been quiet for [`QUIET`]
//!    (at most [`DRAIN_MAX`]), warning about any bytes that still came, and flushes the input;
//! 3. `S` (status): the answer must start with `'2'` and end with LF within 55 bytes (54 is
//!    normal for later IS-900 firmware). A bad or missing answer starts attempt n + 1, except
//!    within [`REBOOT_WINDOW`] after a Ctrl-Y, where `c` and `S` are simply tried again while
//!    the tracker boots;
//! 4. one output-list command per station (`O1,2,11,…,0\r`), `e1,0\r` for a genuine Fastrak
//!    stylus, the filter commands `x0.2,0.2,0.8,0.8\r` and `v0.2,0.2,0.8,0.8\r`, each followed
//!    by [`COMMAND_GAP`];
//! 5. the extra commands from the configuration (each followed by CR; `*N` pauses N seconds);
//! 6. `S` again, as a barrier: the tracker handles commands in order, so its status answer
//!    (a line starting with `'2'` as long as the first answer) proves everything before it
//!    was taken. Other lines (replies to the extra commands) are dropped. No answer within
//!    [`BARRIER_TIMEOUT`] starts attempt n + 1;
//! 7. `f` (binary output), with IS-900 timestamps `MT\r` (milliseconds) and `MZ\r` (zero the
//!    clock, whose host time becomes the tracker's time zero), then `C` (continuous output).
//!    C++ zeroes the clock after `C`, so its first records count from the old zero; zeroing
//!    first gives every record a time on the new one.
//!
//! C++ blocks the whole server with fixed sleeps instead: 2 s after every break byte, 20 s
//! after Ctrl-Y, 2 s before and 1 s after the status request, 1 s after each filter command
//! and 2 s after the extra commands (7.2 s for a first, successful attempt). Here every wait
//! that guards an answer ends when the answer comes, so a healthy tracker streams about half
//! a second after the port opens.

use std::fmt;
use std::time::{Duration, Instant};

use crate::devices::text::TextSeverity;
use crate::serial::PortOps;
use crate::time::{Now, TimeVal};

/// Pause after each break byte (the tracker does not answer them; C++ waits 2 s).
pub const BREAK_GAP: Duration = Duration::from_millis(100);
/// Silence after `c` that shows continuous output has stopped.
pub const QUIET: Duration = Duration::from_millis(100);
/// Longest wait for that silence before asking for status anyway.
pub const DRAIN_MAX: Duration = Duration::from_secs(2);
/// Pause after each configuration command (as C++; they have no answer and are cheap).
pub const COMMAND_GAP: Duration = Duration::from_millis(50);
/// Time a tracker has to answer a status request, on top of the 55 bytes' transmission.
pub const STATUS_TIMEOUT: Duration = Duration::from_secs(1);
/// Time to answer the barrier status request, on top of the 55 bytes' transmission.
pub const BARRIER_TIMEOUT: Duration = Duration::from_secs(2);
/// How long after Ctrl-Y status requests are retried while the tracker reinitialises (C++
/// waits a fixed 20 s).
pub const REBOOT_WINDOW: Duration = Duration::from_secs(25);

/// Ctrl-Y: reinitialise the tracker.
const CTRL_Y: u8 = 0x19;
/// Longest status answer.
const STATUS_LEN: usize = 55;
/// Longest line kept while looking for the barrier's status answer.
const LINE_MAX: usize = 128;

/// Receives the VRPN text messages the sequence sends (the driver forwards them from the
/// tracker's sender).
pub trait Say {
    /// One message.
    fn say(&mut self, severity: TextSeverity, args: fmt::Arguments<'_>);
}

/// One step of the extra reset commands.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Extra {
    /// Bytes to write, CR included.
    Command(Vec<u8>),
    /// A pause.
    Pause(Duration),
}

/// What the sequence sends besides its fixed bytes.
#[derive(Clone, Debug)]
pub struct ResetPlan {
    /// Output-list, stylus-format and filter commands, CR included, in order.
    pub commands: Vec<Vec<u8>>,
    /// Extra commands from the configuration.
    pub extra: Vec<Extra>,
    /// Zero the IS-900 clock and use its timestamps.
    pub is900_time: bool,
    /// Line speed, for transmission times.
    pub baud: u32,
}

/// Where the sequence is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Idle,
    Break {
        next: usize,
    },
    Quiet {
        started: Instant,
        last_input: Instant,
        got: usize,
    },
    Status {
        deadline: Instant,
    },
    Configure {
        next: usize,
    },
    Extra {
        next: usize,
    },
    Barrier {
        deadline: Instant,
    },
    Done,
}

/// What a call to the sequence ended with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still resetting (or idle).
    Busy,
    /// Continuous output was requested: records follow. With IS-900 timestamps, the host
    /// time of the tracker's clock zero.
    Done {
        /// Host time of the tracker clock's zero (IS-900 timestamps only).
        clock_zero: Option<TimeVal>,
    },
}

/// The reset sequence of one tracker.
#[derive(Debug)]
pub struct ResetSequence {
    plan: ResetPlan,
    attempts: u32,
    stage: Stage,
    wake: Option<Instant>,
    reboot_until: Option<Instant>,
    line: [u8; LINE_MAX],
    line_len: usize,
    /// Length of the first status answer, which the barrier's answer must repeat.
    status_len: usize,
}

/// Time to send `bytes` bytes at `baud` (10 bits a byte), rounded up to the microsecond.
pub fn transmission_time(bytes: usize, baud: u32) -> Duration {
    let bits = bytes as u64 * 10 * 1_000_000;
    Duration::from_micros(bits.div_ceil(u64::from(baud.max(1))))
}

impl ResetSequence {
    /// A sequence for `plan`, idle until [`start`](Self::start).
    pub fn new(plan: ResetPlan) -> ResetSequence {
        ResetSequence {
            plan,
            attempts: 0,
            stage: Stage::Idle,
            wake: None,
            reboot_until: None,
            line: [0; LINE_MAX],
            line_len: 0,
            status_len: STATUS_LEN,
        }
    }

    /// The current attempt number (0 after a good status answer).
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// True while a reset is under way.
    pub fn is_busy(&self) -> bool {
        !matches!(self.stage, Stage::Idle | Stage::Done)
    }

    /// Stops without finishing (the port closed).
    pub fn stop(&mut self) {
        self.stage = Stage::Idle;
        self.wake = None;
        self.reboot_until = None;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        if self.wake.is_some() {
            return self.wake;
        }
        match self.stage {
            Stage::Quiet {
                started,
                last_input,
                ..
            } => Some((last_input + QUIET).min(started + DRAIN_MAX)),
            Stage::Status { deadline } | Stage::Barrier { deadline } => Some(deadline),
            _ => None,
        }
    }

    /// Begins the next attempt.
    pub fn start(&mut self, now: Now, port: &mut PortOps, say: &mut dyn Say) -> Progress {
        self.attempts += 1;
        say.say(
            TextSeverity::Warning,
            format_args!("Resetting the tracker (attempt {})", self.attempts),
        );
        self.reboot_until = None;
        self.wake = None;
        self.stage = Stage::Break { next: 0 };
        self.poll(now, port, say)
    }

    /// The break bytes of the current attempt, in sending order.
    fn break_bytes(&self) -> ([u8; 4], usize) {
        let n = self.attempts;
        let mut bytes = [0; 4];
        let mut len = 0;
        for (byte, when) in [
            (b'\r', n > 1),
            (b'Y', n > 5),
            (b't', n > 4),
            (CTRL_Y, n > 2),
        ] {
            if when {
                bytes[len] = byte;
                len += 1;
            }
        }
        (bytes, len)
    }

    fn start_probe(&mut self, now: Now, port: &mut PortOps) {
        port.write(b"c");
        port.flush_input();
        self.stage = Stage::Quiet {
            started: now.mono,
            last_input: now.mono,
            got: 0,
        };
    }

    fn status_timeout(&self, extra: Duration) -> Duration {
        extra + transmission_time(STATUS_LEN, self.plan.baud)
    }

    fn ask_status(&mut self, now: Now, port: &mut PortOps, wait: Duration) -> Instant {
        port.write(b"S");
        self.line_len = 0;
        now.mono + self.status_timeout(wait)
    }

    /// A missing or bad status answer: retry while the tracker reboots, else next attempt.
    fn probe_failed(&mut self, now: Now, port: &mut PortOps, say: &mut dyn Say) -> Progress {
        if self.reboot_until.is_some_and(|t| now.mono < t) {
            self.start_probe(now, port);
            return Progress::Busy;
        }
        say.say(
            TextSeverity::Error,
            format_args!("Bad status report from Fastrak, retrying reset"),
        );
        self.start(now, port, say)
    }

    /// Time-driven steps.
    pub fn poll(&mut self, now: Now, port: &mut PortOps, say: &mut dyn Say) -> Progress {
        loop {
            if let Some(wake) = self.wake {
                if now.mono < wake {
                    return Progress::Busy;
                }
                self.wake = None;
            }
            match self.stage {
                Stage::Idle | Stage::Done => return Progress::Busy,
                Stage::Break { next } => {
                    let (bytes, len) = self.break_bytes();
                    if next < len {
                        port.write(&bytes[next..next + 1]);
                        if bytes[next] == CTRL_Y {
                            self.reboot_until = Some(now.mono + REBOOT_WINDOW);
                        }
                        self.stage = Stage::Break { next: next + 1 };
                        self.wake = Some(now.mono + BREAK_GAP);
                    } else {
                        self.start_probe(now, port);
                    }
                }
                Stage::Quiet {
                    started,
                    last_input,
                    got,
                } => {
                    if now.mono < (last_input + QUIET).min(started + DRAIN_MAX) {
                        return Progress::Busy;
                    }
                    if got > 0 {
                        say.say(
                            TextSeverity::Warning,
                            format_args!("Got >={got} characters after reset"),
                        );
                    }
                    port.flush_input();
                    let deadline = self.ask_status(now, port, STATUS_TIMEOUT);
                    self.stage = Stage::Status { deadline };
                }
                Stage::Status { deadline } => {
                    if now.mono < deadline {
                        return Progress::Busy;
                    }
                    return self.probe_failed(now, port, say);
                }
                Stage::Configure { next } => {
                    if let Some(cmd) = self.plan.commands.get(next) {
                        port.write(cmd);
                        self.stage = Stage::Configure { next: next + 1 };
                        self.wake = Some(now.mono + COMMAND_GAP);
                    } else {
                        self.stage = Stage::Extra { next: 0 };
                    }
                }
                Stage::Extra { next } => {
                    match self.plan.extra.get(next) {
                        Some(Extra::Command(cmd)) => port.write(cmd),
                        Some(Extra::Pause(d)) => self.wake = Some(now.mono + *d),
                        None => {
                            let deadline = self.ask_status(now, port, BARRIER_TIMEOUT);
                            self.stage = Stage::Barrier { deadline };
                            continue;
                        }
                    }
                    self.stage = Stage::Extra { next: next + 1 };
                }
                Stage::Barrier { deadline } => {
                    if now.mono < deadline {
                        return Progress::Busy;
                    }
                    say.say(
                        TextSeverity::Error,
                        format_args!(
                            "No status answer after the configuration commands, retrying reset"
                        ),
                    );
                    return self.start(now, port, say);
                }
            }
        }
    }

    /// Bytes from the tracker while resetting.
    pub fn received(
        &mut self,
        bytes: &[u8],
        arrived: Now,
        port: &mut PortOps,
        say: &mut dyn Say,
    ) -> Progress {
        match &mut self.stage {
            Stage::Quiet {
                last_input, got, ..
            } => {
                *last_input = arrived.mono;
                *got += bytes.len();
                Progress::Busy
            }
            Stage::Status { .. } => {
                for &b in bytes {
                    match self.status_byte(b) {
                        StatusByte::More => {}
                        StatusByte::Bad => return self.probe_failed(arrived, port, say),
                        StatusByte::Good(len) => {
                            if len != STATUS_LEN && len != STATUS_LEN - 1 {
                                say.say(
                                    TextSeverity::Normal,
                                    format_args!("Got {len} of 55 characters for status"),
                                );
                            }
                            say.say(
                                TextSeverity::Warning,
                                format_args!("Fastrak/Isense gives status (this is good)"),
                            );
                            self.attempts = 0;
                            self.status_len = len;
                            self.reboot_until = None;
                            self.stage = Stage::Configure { next: 0 };
                            // Bytes after the answer are stale; the sequence goes on.
                            return self.poll(arrived, port, say);
                        }
                    }
                }
                Progress::Busy
            }
            Stage::Barrier { .. } => {
                for &b in bytes {
                    if self.barrier_byte(b) {
                        return self.finish(arrived, port);
                    }
                }
                Progress::Busy
            }
            _ => Progress::Busy,
        }
    }

    /// One byte of the answer to the first status request: it must start with `'2'` and end
    /// with LF within 55 bytes.
    fn status_byte(&mut self, b: u8) -> StatusByte {
        if self.line_len == 0 && b != b'2' {
            return StatusByte::Bad;
        }
        self.line_len += 1;
        if b == b'\n' {
            StatusByte::Good(self.line_len)
        } else if self.line_len >= STATUS_LEN {
            StatusByte::Bad
        } else {
            StatusByte::More
        }
    }

    /// One byte while waiting for the barrier's status answer: a line starting with `'2'` as
    /// long (LF included) as the first answer. Other lines are replies to earlier commands.
    fn barrier_byte(&mut self, b: u8) -> bool {
        if self.line_len < LINE_MAX {
            self.line[self.line_len] = b;
        }
        self.line_len += 1;
        if b != b'\n' {
            return false;
        }
        let len = std::mem::take(&mut self.line_len);
        self.line[0] == b'2' && len == self.status_len
    }

    fn finish(&mut self, now: Now, port: &mut PortOps) -> Progress {
        port.flush_input();
        port.write(b"f");
        let mut clock_zero = None;
        if self.plan.is900_time {
            const UNITS_AND_ZERO: &[u8] = b"MT\rMZ\r";
            port.write(UNITS_AND_ZERO);
            // The tracker zeroes its clock when it reads the last byte, which leaves the port
            // once everything written in this call has been transmitted.
            let sent = transmission_time(1 + UNITS_AND_ZERO.len(), self.plan.baud);
            clock_zero = Some(now.wall.plus(sent));
        }
        port.write(b"C");
        self.stage = Stage::Done;
        Progress::Done { clock_zero }
    }
}

enum StatusByte {
    More,
    Bad,
    Good(usize),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::serial::PortOp;

    #[derive(Default)]
    struct Texts(Vec<(TextSeverity, String)>);

    impl Say for Texts {
        fn say(&mut self, severity: TextSeverity, args: fmt::Arguments<'_>) {
            self.0.push((severity, args.to_string()));
        }
    }

    fn plan() -> ResetPlan {
        ResetPlan {
            commands: vec![b"O1,2,11,0\r".to_vec()],
            extra: vec![],
            is900_time: false,
            baud: 9600,
        }
    }

    fn start() -> Now {
        Now {
            mono: Instant::now(),
            wall: TimeVal::new(5000, 0),
        }
    }

    /// Writes in `ops`, concatenated.
    fn written(ops: &PortOps) -> Vec<u8> {
        let mut out = Vec::new();
        for op in ops.ops() {
            if let PortOp::Write { start, len } = *op {
                out.extend_from_slice(ops.write_bytes(start, len));
            }
        }
        out
    }

    /// Runs attempt `n` with no answers until its status request; returns every byte
    /// written and the time from the start of the attempt to the status request.
    fn attempt(n: u32) -> (Vec<u8>, Duration) {
        let mut seq = ResetSequence::new(plan());
        seq.attempts = n - 1;
        let mut texts = Texts::default();
        let mut ops = PortOps::new();
        let t0 = start();
        let mut now = t0;
        seq.start(now, &mut ops, &mut texts);
        let mut out = written(&ops);
        ops.clear();
        while !matches!(seq.stage, Stage::Status { .. }) {
            now = now.plus(seq.deadline().unwrap() - now.mono);
            seq.poll(now, &mut ops, &mut texts);
            out.extend(written(&ops));
            ops.clear();
        }
        assert_eq!(texts.0[0].1, format!("Resetting the tracker (attempt {n})"));
        (out, now.mono - t0.mono)
    }

    #[test]
    fn break_bytes_escalate_with_the_attempt() {
        assert_eq!(attempt(1), (b"cS".to_vec(), QUIET));
        assert_eq!(attempt(2), (b"\rcS".to_vec(), BREAK_GAP + QUIET));
        assert_eq!(attempt(3).0, b"\r\x19cS");
        assert_eq!(attempt(4).0, b"\r\x19cS");
        assert_eq!(attempt(5).0, b"\rt\x19cS");
        assert_eq!(attempt(6).0, b"\rYt\x19cS");
        assert_eq!(attempt(9).0, b"\rYt\x19cS");
    }

    #[test]
    fn bad_status_starts_the_next_attempt_and_good_status_resets_the_count() {
        let mut seq = ResetSequence::new(plan());
        let (mut texts, mut ops) = (Texts::default(), PortOps::new());
        let mut now = start();
        seq.start(now, &mut ops, &mut texts);
        now = now.plus(QUIET);
        seq.poll(now, &mut ops, &mut texts);
        // Garbage instead of '2': at once the second attempt.
        seq.received(b"x", now, &mut ops, &mut texts);
        assert_eq!(seq.attempts(), 2);
        assert!(texts
            .0
            .iter()
            .any(|(s, t)| *s == TextSeverity::Error && t.contains("Bad status report")));
        now = now.plus(BREAK_GAP);
        seq.poll(now, &mut ops, &mut texts);
        now = now.plus(QUIET);
        seq.poll(now, &mut ops, &mut texts);
        assert!(matches!(seq.stage, Stage::Status { .. }));
        ops.clear();
        let mut answer = b"21S".to_vec();
        answer.resize(50, b' ');
        answer.extend_from_slice(b"\r\n");
        // An unusual length is accepted, noted, and expected again from the barrier.
        assert_eq!(
            seq.received(&answer, now, &mut ops, &mut texts),
            Progress::Busy
        );
        assert_eq!(seq.attempts(), 0);
        assert!(texts
            .0
            .iter()
            .any(|(_, t)| t == "Got 52 of 55 characters for status"));
        assert_eq!(written(&ops), b"O1,2,11,0\r");
        now = now.plus(COMMAND_GAP);
        ops.clear();
        seq.poll(now, &mut ops, &mut texts);
        assert_eq!(written(&ops), b"S");
        // A reply line of another length is skipped; the status answer ends the sequence.
        let mut replies = b"2 E error\r\n".to_vec();
        replies.extend_from_slice(&answer);
        ops.clear();
        let done = seq.received(&replies, now, &mut ops, &mut texts);
        assert_eq!(done, Progress::Done { clock_zero: None });
        assert_eq!(written(&ops), b"fC");
        assert_eq!(ops.ops()[0], PortOp::FlushInput);
    }

    #[test]
    fn status_times_out_after_a_second_plus_transmission() {
        let mut seq = ResetSequence::new(plan());
        let (mut texts, mut ops) = (Texts::default(), PortOps::new());
        let mut now = start();
        seq.start(now, &mut ops, &mut texts);
        now = now.plus(QUIET);
        seq.poll(now, &mut ops, &mut texts);
        let wait = seq.deadline().unwrap() - now.mono;
        assert_eq!(wait, STATUS_TIMEOUT + transmission_time(55, 9600));
        assert_eq!(transmission_time(55, 9600), Duration::from_micros(57_292));
        now = now.plus(wait);
        seq.poll(now, &mut ops, &mut texts);
        assert_eq!(seq.attempts(), 2);
    }

    #[test]
    fn is900_clock_zero_is_when_mz_has_left_the_port() {
        let mut p = plan();
        p.is900_time = true;
        p.commands.clear();
        let mut seq = ResetSequence::new(p);
        let (mut texts, mut ops) = (Texts::default(), PortOps::new());
        let now = start();
        seq.start(now, &mut ops, &mut texts);
        seq.poll(now.plus(QUIET), &mut ops, &mut texts);
        let mut answer = b"21S".to_vec();
        answer.resize(53, b'.');
        answer.extend_from_slice(b"\r\n");
        seq.received(&answer, now.plus(QUIET), &mut ops, &mut texts);
        ops.clear();
        let at = now.plus(Duration::from_millis(300));
        let p = seq.received(&answer, at, &mut ops, &mut texts);
        // 'f' and "MT\rMZ\r" are 7 bytes: 7.292 ms at 9600 baud.
        assert_eq!(
            p,
            Progress::Done {
                clock_zero: Some(at.wall.plus(Duration::from_micros(7292)))
            }
        );
        assert_eq!(written(&ops), b"fMT\rMZ\rC");
    }
}
