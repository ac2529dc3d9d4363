//! The Immersion Interface Box's reset as a state machine over deadlines (pure code).
//!
//! | Step | Written | Waits for |
//! |---|---|---|
//! | end | `E` (ends a session still open) | 10 ms |
//! | sync | `IMMC` (the box learns the baud rate from it) | the echo `IMMC` within 65 ms, else `E` and `IMMC` again; at most 10 s in all |
//! | begin | `BEGIN` | `IBOX` within 50 ms plus the bytes' transmission |
//! | identify | each of `C8`…`CE` (name, product id, model, serial number, comment, parameter file, version) | the command echoed (bit 7 set) and a text, ended by a NUL byte (or 31 characters, or 115 ms) |
//! | configure | 25 bytes: `CF 00 0A` (a record every 10 ms), the configuration byte, 21 zeros | the echo `CF` within 100 ms plus transmission |
//!
//! Every byte after the configuration's echo is the record stream.

use std::time::{Duration, Instant};

use crate::serial::PortOps;
use crate::time::Now;

/// Ends a session the box may still be in.
pub const END_SESSION: &[u8] = b"E";
/// The synchronisation string, echoed by the box.
pub const SYNC: &[u8] = b"IMMC";
/// Starts a session.
pub const BEGIN: &[u8] = b"BEGIN";
/// The box's answer to `BEGIN`.
pub const BOX_ANSWER: &[u8] = b"IBOX";
/// The identification commands, in the order sent.
pub const IDENT_COMMANDS: [u8; 7] = [0xC8, 0xC9, 0xCA, 0xCB, 0xCC, 0xCD, 0xCE];
/// What each identification command asks for.
pub const IDENT_NAMES: [&str; 7] = [
    "name",
    "product id",
    "model",
    "serial number",
    "comment",
    "parameter file",
    "version",
];
/// The configuration command's first byte, echoed by the box.
pub const CONFIGURE: u8 = 0xCF;
/// Milliseconds between records asked for.
pub const RECORD_PERIOD_MS: u8 = 10;

/// Pause after `E`.
pub const END_PAUSE: Duration = Duration::from_millis(10);
/// Time for the `IMMC` echo before it is sent again (C++: 15 ms pause, 50 ms read).
pub const SYNC_WAIT: Duration = Duration::from_millis(65);
/// Longest synchronisation (C++'s 10 s).
pub const SYNC_LIMIT: Duration = Duration::from_secs(10);
/// Time for `IBOX` after `BEGIN`, besides transmission.
pub const BEGIN_WAIT: Duration = Duration::from_millis(50);
/// Time for an identification answer (C++: 100 ms pause, 15 ms read).
pub const IDENT_WAIT: Duration = Duration::from_millis(115);
/// Longest identification text kept.
pub const IDENT_LEN: usize = 31;
/// Time for the configuration's echo, besides transmission.
pub const CONFIGURE_WAIT: Duration = Duration::from_millis(100);

/// The 25-byte configuration command for a configuration byte.
pub fn configure_command(config: u8) -> [u8; 25] {
    let mut c = [0u8; 25];
    c[0] = CONFIGURE;
    c[2] = RECORD_PERIOD_MS;
    c[3] = config;
    c
}

/// Why an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// No `IMMC` echo within [`SYNC_LIMIT`].
    NoSync,
    /// No `IBOX` after `BEGIN` (the bytes that came instead, if any: up to four).
    NotABox([u8; 4], usize),
    /// An identification command got no (or a wrong) answer.
    Ident(usize),
    /// The configuration was not echoed.
    NoConfigureEcho,
}

/// What a call led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still working.
    Working,
    /// Done: the bytes of this read from this index on are records.
    Done(usize),
    /// The attempt failed.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    End,
    Sync,
    Begin,
    Ident(usize),
    Configure,
}

/// One identification text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Text {
    bytes: [u8; IDENT_LEN],
    len: usize,
}

impl Text {
    const EMPTY: Text = Text {
        bytes: [0; IDENT_LEN],
        len: 0,
    };

    /// The text's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

/// The reset in progress. See the module documentation.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    config: u8,
    baud: u32,
    step: Step,
    started: Option<Instant>,
    deadline: Option<Instant>,
    /// Bytes matched of the string waited for, or bytes of the current answer.
    matched: usize,
    got: [u8; 4],
    echoed: bool,
    ident: [Text; 7],
}

impl ResetSequence {
    /// The reset for configuration byte `config` on a line at `baud`.
    pub fn new(config: u8, baud: u32) -> ResetSequence {
        ResetSequence {
            config,
            baud,
            step: Step::Idle,
            started: None,
            deadline: None,
            matched: 0,
            got: [0; 4],
            echoed: false,
            ident: [Text::EMPTY; 7],
        }
    }

    /// The identification texts of the last reset that got them.
    pub fn ident(&self) -> &[Text; 7] {
        &self.ident
    }

    /// When the next step is due.
    pub fn deadline(&self) -> Option<Instant> {
        self.deadline
    }

    /// Forgets the attempt.
    pub fn stop(&mut self) {
        self.step = Step::Idle;
        self.deadline = None;
    }

    fn transmission(&self, bytes: usize) -> Duration {
        Duration::from_micros(bytes as u64 * 10_000_000 / u64::from(self.baud.max(1)))
    }

    /// Starts an attempt: flushes the input and ends a session left open.
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        port.flush_input();
        port.write(END_SESSION);
        self.step = Step::End;
        self.started = Some(now.mono);
        self.deadline = Some(now.mono + END_PAUSE);
    }

    fn send_sync(&mut self, now: Instant, port: &mut PortOps) {
        port.write(SYNC);
        self.step = Step::Sync;
        self.matched = 0;
        self.deadline = Some(now + SYNC_WAIT + self.transmission(SYNC.len() * 2));
    }

    fn send_ident(&mut self, i: usize, now: Instant, port: &mut PortOps) {
        port.write(&[IDENT_COMMANDS[i]]);
        self.step = Step::Ident(i);
        self.matched = 0;
        self.echoed = false;
        self.ident[i] = Text::EMPTY;
        self.deadline = Some(now + IDENT_WAIT + self.transmission(1 + IDENT_LEN));
    }

    fn next_after_ident(&mut self, i: usize, now: Instant, port: &mut PortOps) {
        if i + 1 < IDENT_COMMANDS.len() {
            self.send_ident(i + 1, now, port);
        } else {
            port.write(&configure_command(self.config));
            self.step = Step::Configure;
            self.deadline = Some(now + CONFIGURE_WAIT + self.transmission(26));
        }
    }

    /// A deadline passed.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        if self.deadline.map_or(true, |d| now.mono < d) {
            return Progress::Working;
        }
        let fail = |s: &mut Self, f| {
            s.stop();
            Progress::Failed(f)
        };
        match self.step {
            Step::Idle => Progress::Working,
            Step::End => {
                self.send_sync(now.mono, port);
                Progress::Working
            }
            Step::Sync => {
                if self.started.is_some_and(|s| now.mono >= s + SYNC_LIMIT) {
                    return fail(self, Failure::NoSync);
                }
                // `E` again first: a box still in a session (its echo was lost) ignores IMMC.
                port.write(END_SESSION);
                self.step = Step::End;
                self.deadline = Some(now.mono + END_PAUSE);
                Progress::Working
            }
            Step::Begin => fail(self, Failure::NotABox(self.got, self.matched)),
            Step::Ident(i) if self.echoed => {
                // A text without its NUL: keep what came.
                self.next_after_ident(i, now.mono, port);
                Progress::Working
            }
            Step::Ident(i) => fail(self, Failure::Ident(i)),
            Step::Configure => fail(self, Failure::NoConfigureEcho),
        }
    }

    /// Bytes arrived.
    pub fn received(&mut self, bytes: &[u8], now: Now, port: &mut PortOps) -> Progress {
        for (i, &b) in bytes.iter().enumerate() {
            match self.step {
                Step::Idle | Step::End => {}
                Step::Sync => {
                    // Looks for IMMC anywhere (bytes the box sent before it synchronised).
                    if b == SYNC[self.matched] {
                        self.matched += 1;
                    } else {
                        self.matched = usize::from(b == SYNC[0]);
                    }
                    if self.matched == SYNC.len() {
                        port.flush_input();
                        port.write(BEGIN);
                        self.step = Step::Begin;
                        self.matched = 0;
                        self.deadline =
                            Some(now.mono + BEGIN_WAIT + self.transmission(BEGIN.len() + 4));
                        // The rest of this read is stale (flushed).
                        return Progress::Working;
                    }
                }
                Step::Begin => {
                    self.got[self.matched] = b;
                    self.matched += 1;
                    if self.matched == BOX_ANSWER.len() {
                        if self.got != BOX_ANSWER {
                            return {
                                self.stop();
                                Progress::Failed(Failure::NotABox(self.got, 4))
                            };
                        }
                        self.send_ident(0, now.mono, port);
                    }
                }
                Step::Ident(n) => {
                    if !self.echoed {
                        if b & 0x80 == 0 || b & 0x7F != IDENT_COMMANDS[n] & 0x7F {
                            self.stop();
                            return Progress::Failed(Failure::Ident(n));
                        }
                        self.echoed = true;
                        continue;
                    }
                    let text = &mut self.ident[n];
                    if b != 0 && text.len < IDENT_LEN {
                        text.bytes[text.len] = b;
                        text.len += 1;
                    }
                    if b == 0 || text.len == IDENT_LEN {
                        self.next_after_ident(n, now.mono, port);
                    }
                }
                Step::Configure => {
                    if b == CONFIGURE {
                        self.stop();
                        return Progress::Done(i + 1);
                    }
                }
            }
        }
        Progress::Working
    }
}
