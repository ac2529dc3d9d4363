//! The reset of a Flock through its master bird's serial line, as a state machine over
//! deadlines, and the query that asks a failed Flock for its error code.
//!
//! # Commands used
//!
//! | Bytes | Meaning |
//! |---|---|
//! | `'B'` | point mode: stops streaming (in point mode it asks for one record) |
//! | `'@'` | stream mode: records flow at the measurement rate |
//! | `'G'` | sleep: the transmitter stops |
//! | `'O'` p | examine value p; the answer is raw bytes, no phasing bit |
//! | `'P'` p v… | change value p |
//! | `0xF0 + a` | forward the next command to the bird at bus address a |
//! | `']'` | position/quaternion output format (for the addressed bird) |
//! | `'L'` h s | hemisphere: (h, s) = +X (0,0), −X (0,1), +Y (6,0), −Y (6,1), +Z (12,0), −Z (12,1) |
//!
//! Examined values: 0 = bird status (2 bytes), 2 = crystal speed (2 bytes, the first is the
//! MHz), 6 = measurement-rate count (2 bytes, little-endian), 16 = expanded error code (2
//! bytes: code, address/command), 36 = system status (14 bytes, one per bus address from 1:
//! bit 7 accessible, bit 6 running, bit 5 receiver). Changed values: 35 = group mode (1 byte),
//! 50 = bus auto-configuration (1 byte: the number of units).
//!
//! # Sequence
//!
//! 1. Raise RTS for [`RTS_PULSE`], then drop it (resets the master bird's serial interface
//!    when RTS is wired; on a pseudo-terminal the request fails harmlessly).
//! 2. Send `'B'` (stop a stream left running), wait until the line has been quiet for
//!    [`QUIET`], discard the input, and ask for the bird status. No answer within
//!    [`PROBE_WAIT`]: the bird is still starting (a `'B'` it missed then does not matter: a
//!    bird that starts does not stream); ask again until [`BOOT_LIMIT`] after RTS dropped.
//! 3. [`AUTOCONFIG_PAUSE`] after the answer, send the auto-configuration (`'P'` 50, units);
//!    [`AUTOCONFIG_PAUSE`] later, discard the input and ask for the system status. The Flock's
//!    manual asks for 300 ms of silence before and after the auto-configuration.
//! 4. Every unit (the receivers, and the extended-range controller when present) must be
//!    accessible and running. After a short answer, or one showing a unit not yet up, the
//!    status is asked for again, until [`AUTOCONFIG_LIMIT`] after the auto-configuration;
//!    then the reset fails.
//! 5. Send group mode on, the position/quaternion format and the hemisphere to every receiver
//!    (forwarded by address), and ask for the crystal speed and the measurement-rate count
//!    (answered within [`REPLY_WAIT`], or the rate stays unknown: not a failure).
//! 6. In stream mode, send `'@'`.
//!
//! C++ VRPN sleeps instead: 1 s with RTS up, 2 s after, 5 s after `'B'`, 10 s after the
//! auto-configuration, 0.5 s for each answer (≈ 19 s). Here each wait ends when the answer
//! it waits for arrives, and only the pauses the device itself requires remain: a Flock that
//! answers at once is streaming about 0.8 s after the port opens.

use std::time::{Duration, Instant};

use super::config::Hemisphere;
use super::record::Transmitter;
use crate::serial::PortOps;
use crate::time::Now;

/// How long RTS is held up (C++: 1 s).
pub const RTS_PULSE: Duration = Duration::from_millis(100);
/// Silence on the line that shows a stream has stopped (at 2400 baud a byte takes 4 ms).
pub const QUIET: Duration = Duration::from_millis(100);
/// How long a bird-status probe waits for its two bytes before asking again (they take 8 ms
/// at 2400 baud; a late answer still counts for the next probe).
pub const PROBE_WAIT: Duration = Duration::from_millis(100);
/// How long after RTS drops the bird may take to answer a probe (C++ waits 7 s in all
/// before its first question).
pub const BOOT_LIMIT: Duration = Duration::from_secs(5);
/// Silence the Flock requires before and after the auto-configuration command.
pub const AUTOCONFIG_PAUSE: Duration = Duration::from_millis(300);
/// How long an answer to an examine command may take (C++ sleeps this long, then reads).
pub const REPLY_WAIT: Duration = Duration::from_millis(500);
/// Pause before asking again for a system status that showed units not yet running.
pub const STATUS_RETRY: Duration = Duration::from_millis(250);
/// How long after the auto-configuration every unit must be running (C++ sleeps this long).
pub const AUTOCONFIG_LIMIT: Duration = Duration::from_secs(10);

/// Point mode / single record.
pub const POINT: u8 = b'B';
/// Stream mode.
pub const STREAM: u8 = b'@';
/// Sleep.
pub const SLEEP: u8 = b'G';
/// Change value.
pub const CHANGE_VALUE: u8 = b'P';
/// Examine value.
pub const EXAMINE_VALUE: u8 = b'O';
/// Position/quaternion output format.
pub const POSITION_QUATERNION: u8 = b']';
/// Hemisphere.
pub const HEMISPHERE: u8 = b'L';
/// Forward the next command to bus address `a`: `TO_ADDRESS + a`.
pub const TO_ADDRESS: u8 = 0xF0;

/// Examine: bird status (2 bytes).
pub const BIRD_STATUS: u8 = 0;
/// Examine: crystal speed (2 bytes, MHz first).
pub const CRYSTAL_SPEED: u8 = 2;
/// Examine: measurement-rate count (2 bytes, little-endian).
pub const RATE_COUNT: u8 = 6;
/// Examine: expanded error code (2 bytes).
pub const EXPANDED_ERROR: u8 = 16;
/// Change: group mode (1 byte).
pub const GROUP_MODE: u8 = 35;
/// Examine: system status (14 bytes).
pub const SYSTEM_STATUS: u8 = 36;
/// Change: bus auto-configuration (1 byte: units).
pub const AUTOCONFIG: u8 = 50;

/// Bytes of the system-status answer: one per bus address 1..=14.
pub const STATUS_LEN: usize = 14;
/// System status: the unit answers on the bus.
pub const UNIT_ACCESSIBLE: u8 = 0x80;
/// System status: the unit is running (flying).
pub const UNIT_RUNNING: u8 = 0x40;
/// System status: the unit is a receiver (else a transmitter or controller).
pub const UNIT_RECEIVER: u8 = 0x20;

/// The hemisphere command's two argument bytes.
pub fn hemisphere_bytes(h: Hemisphere) -> [u8; 2] {
    match h {
        Hemisphere::PosX => [0x00, 0x00],
        Hemisphere::NegX => [0x00, 0x01],
        Hemisphere::PosY => [0x06, 0x00],
        Hemisphere::NegY => [0x06, 0x01],
        Hemisphere::PosZ => [0x0C, 0x00],
        Hemisphere::NegZ => [0x0C, 0x01],
    }
}

/// The measurement rate the crystal speed (MHz) and rate count give, in Hz.
pub fn measurement_rate(crystal_mhz: u8, count: u16) -> Option<f64> {
    if crystal_mhz == 0 {
        return None;
    }
    let ms = 4.0 * (f64::from(count) * (8.0 / f64::from(crystal_mhz)) / 1000.0) + 0.3;
    Some(1000.0 / ms)
}

/// What a reset sets up.
#[derive(Clone, Debug)]
pub struct ResetPlan {
    /// Receivers on the bus.
    pub receivers: u8,
    /// The transmitter (an extended-range one adds its controller at address 1).
    pub transmitter: Transmitter,
    /// Hemisphere for every receiver.
    pub hemisphere: Hemisphere,
    /// Send `'@'` at the end (the master of a parallel Flock stays in point mode).
    pub stream: bool,
}

impl ResetPlan {
    /// Units the auto-configuration and the status check cover.
    pub fn units(&self) -> u8 {
        self.transmitter.units(self.receivers)
    }

    /// Group mode on, then the output format and hemisphere of every receiver.
    pub fn mode_commands(&self) -> Vec<u8> {
        let first = self.transmitter.first_receiver_address();
        let mut out = vec![CHANGE_VALUE, GROUP_MODE, 1];
        for a in first..first + self.receivers {
            out.extend_from_slice(&[TO_ADDRESS + a, POSITION_QUATERNION]);
        }
        let [h, s] = hemisphere_bytes(self.hemisphere);
        for a in first..first + self.receivers {
            out.extend_from_slice(&[TO_ADDRESS + a, HEMISPHERE, h, s]);
        }
        out
    }
}

/// Why a reset failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// The bird never answered the bird-status probe.
    NoAnswer,
    /// Bytes kept arriving after `'B'`: the line never fell quiet.
    NeverQuiet,
    /// The system status never arrived whole (bytes received of the last request).
    StatusIncomplete(usize),
    /// Some unit was not accessible or not running when time ran out.
    UnitsDown([u8; STATUS_LEN]),
}

/// What a finished reset learnt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// The system status the check accepted.
    pub status: [u8; STATUS_LEN],
    /// Crystal speed in MHz and the measurement rate in Hz, if the Flock answered.
    pub rate: Option<(u8, f64)>,
}

/// Where a reset stands after a call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// Still working (or idle).
    Working,
    /// Finished: the Flock is configured (and streaming in stream mode).
    Done(Outcome),
    /// Failed: the port should be reopened and the reset run again.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug)]
enum State {
    Idle,
    RtsUp {
        until: Instant,
    },
    Quiet {
        until: Instant,
        heard: bool,
    },
    Probe {
        until: Instant,
        got: usize,
    },
    BeforeAutoconfig {
        until: Instant,
    },
    AfterAutoconfig {
        until: Instant,
    },
    Status {
        until: Instant,
        got: usize,
        buf: [u8; STATUS_LEN],
    },
    StatusAgain {
        until: Instant,
    },
    Rate {
        until: Instant,
        got: usize,
        buf: [u8; 4],
        status: [u8; STATUS_LEN],
    },
}

/// The master line's reset.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    plan: ResetPlan,
    mode_commands: Vec<u8>,
    state: State,
    /// Set when RTS drops: the bird must have answered a probe by then.
    boot_deadline: Option<Instant>,
    /// Set when the auto-configuration is sent: every unit must be running by then.
    autoconfig_deadline: Option<Instant>,
}

impl ResetSequence {
    /// A reset that sets up `plan` (idle until [`start`](Self::start)).
    pub fn new(plan: ResetPlan) -> ResetSequence {
        ResetSequence {
            mode_commands: plan.mode_commands(),
            plan,
            state: State::Idle,
            boot_deadline: None,
            autoconfig_deadline: None,
        }
    }

    /// The plan.
    pub fn plan(&self) -> &ResetPlan {
        &self.plan
    }

    /// True unless idle.
    pub fn is_running(&self) -> bool {
        !matches!(self.state, State::Idle)
    }

    /// Starts over: raises RTS.
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        port.flush_input();
        port.set_rts(true);
        self.state = State::RtsUp {
            until: now.mono + RTS_PULSE,
        };
    }

    /// Stops (the port closed).
    pub fn stop(&mut self) {
        self.state = State::Idle;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.state {
            State::Idle => None,
            // Only a line that keeps talking runs into the boot limit here.
            State::Quiet { until, heard: true } => {
                Some(self.boot_deadline.map_or(until, |b| until.min(b)))
            }
            State::Quiet {
                until,
                heard: false,
            } => Some(until),
            State::RtsUp { until }
            | State::Probe { until, .. }
            | State::BeforeAutoconfig { until }
            | State::AfterAutoconfig { until }
            | State::Status { until, .. }
            | State::StatusAgain { until }
            | State::Rate { until, .. } => Some(until),
        }
    }

    fn stop_stream(&mut self, now: Instant, port: &mut PortOps) {
        port.write(&[POINT]);
        self.state = State::Quiet {
            until: now + QUIET,
            heard: false,
        };
    }

    fn probe(&mut self, now: Instant, port: &mut PortOps) {
        port.flush_input();
        port.write(&[EXAMINE_VALUE, BIRD_STATUS]);
        self.state = State::Probe {
            until: now + PROBE_WAIT,
            got: 0,
        };
    }

    fn ask_status(&mut self, now: Instant, port: &mut PortOps) {
        port.flush_input();
        port.write(&[EXAMINE_VALUE, SYSTEM_STATUS]);
        self.state = State::Status {
            until: now + REPLY_WAIT,
            got: 0,
            buf: [0; STATUS_LEN],
        };
    }

    /// Time-driven steps.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        let t = now.mono;
        if self.deadline().map_or(true, |d| t < d) {
            return Progress::Working;
        }
        match self.state {
            State::Idle => {}
            State::RtsUp { .. } => {
                port.set_rts(false);
                self.boot_deadline = Some(t + BOOT_LIMIT);
                self.stop_stream(t, port);
            }
            State::Quiet { until, .. } => {
                if t < until {
                    // The boot limit passed while bytes kept coming.
                    self.state = State::Idle;
                    return Progress::Failed(Failure::NeverQuiet);
                }
                self.probe(t, port);
            }
            State::Probe { .. } => {
                if self.boot_deadline.map_or(true, |b| t >= b) {
                    self.state = State::Idle;
                    return Progress::Failed(Failure::NoAnswer);
                }
                self.probe(t, port);
            }
            State::BeforeAutoconfig { .. } => {
                port.write(&[CHANGE_VALUE, AUTOCONFIG, self.plan.units()]);
                self.autoconfig_deadline = Some(t + AUTOCONFIG_LIMIT);
                self.state = State::AfterAutoconfig {
                    until: t + AUTOCONFIG_PAUSE,
                };
            }
            State::AfterAutoconfig { .. } | State::StatusAgain { .. } => self.ask_status(t, port),
            State::Status { got, buf, .. } => {
                if self.autoconfig_over(t) {
                    self.state = State::Idle;
                    return Progress::Failed(if got < STATUS_LEN {
                        Failure::StatusIncomplete(got)
                    } else {
                        Failure::UnitsDown(buf)
                    });
                }
                self.ask_status(t, port);
            }
            State::Rate { status, .. } => return self.finish(status, None, port),
        }
        Progress::Working
    }

    /// Bytes that arrived while resetting. Bytes after an answer that completes a step are
    /// dropped: they were sent before the next request.
    pub fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) -> Progress {
        let t = arrived.mono;
        for &b in bytes {
            match &mut self.state {
                State::Quiet { until, heard } => {
                    *until = t + QUIET;
                    *heard = true;
                }
                State::Probe { got, .. } => {
                    *got += 1;
                    if *got == 2 {
                        self.state = State::BeforeAutoconfig {
                            until: t + AUTOCONFIG_PAUSE,
                        };
                    }
                }
                State::Status { got, buf, .. } => {
                    buf[*got] = b;
                    *got += 1;
                    if *got == STATUS_LEN {
                        let status = *buf;
                        return self.check_status(status, t, port);
                    }
                }
                State::Rate {
                    got, buf, status, ..
                } => {
                    buf[*got] = b;
                    *got += 1;
                    if *got == buf.len() {
                        let (buf, status) = (*buf, *status);
                        let count = u16::from_le_bytes([buf[2], buf[3]]);
                        let rate = measurement_rate(buf[0], count).map(|hz| (buf[0], hz));
                        return self.finish(status, rate, port);
                    }
                }
                State::Idle
                | State::RtsUp { .. }
                | State::BeforeAutoconfig { .. }
                | State::AfterAutoconfig { .. }
                | State::StatusAgain { .. } => {}
            }
        }
        Progress::Working
    }

    fn autoconfig_over(&self, t: Instant) -> bool {
        self.autoconfig_deadline.map_or(true, |d| t >= d)
    }

    /// True when every unit the plan needs is accessible and running.
    pub fn units_ok(&self, status: &[u8; STATUS_LEN]) -> bool {
        let need = UNIT_ACCESSIBLE | UNIT_RUNNING;
        status[..usize::from(self.plan.units())]
            .iter()
            .all(|&s| s & need == need)
    }

    fn check_status(
        &mut self,
        status: [u8; STATUS_LEN],
        t: Instant,
        port: &mut PortOps,
    ) -> Progress {
        if !self.units_ok(&status) {
            if self.autoconfig_over(t) {
                self.state = State::Idle;
                return Progress::Failed(Failure::UnitsDown(status));
            }
            self.state = State::StatusAgain {
                until: t + STATUS_RETRY,
            };
            return Progress::Working;
        }
        port.write(&self.mode_commands);
        port.write(&[EXAMINE_VALUE, CRYSTAL_SPEED, EXAMINE_VALUE, RATE_COUNT]);
        self.state = State::Rate {
            until: t + REPLY_WAIT,
            got: 0,
            buf: [0; 4],
            status,
        };
        Progress::Working
    }

    fn finish(
        &mut self,
        status: [u8; STATUS_LEN],
        rate: Option<(u8, f64)>,
        port: &mut PortOps,
    ) -> Progress {
        if self.plan.stream {
            port.write(&[STREAM]);
        }
        self.state = State::Idle;
        Progress::Done(Outcome { status, rate })
    }
}

/// Asks a failed Flock why: `'B'`, `'G'` (stop and sleep), then, once the line is quiet,
/// discards the input and examines the expanded error code (two bytes within
/// [`REPLY_WAIT`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct ErrorQuery {
    state: QueryState,
}

#[derive(Clone, Copy, Debug, Default)]
enum QueryState {
    #[default]
    Idle,
    Quiet {
        until: Instant,
        give_up: Instant,
    },
    Answer {
        until: Instant,
        got: usize,
        buf: [u8; 2],
    },
}

/// Where an error query stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QueryProgress {
    /// Still asking.
    Working,
    /// Finished: the error code and its expansion, if the Flock answered.
    Done(Option<[u8; 2]>),
}

impl ErrorQuery {
    /// Stops streaming and puts the Flock to sleep.
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        port.write(&[POINT, SLEEP]);
        self.state = QueryState::Quiet {
            until: now.mono + QUIET,
            give_up: now.mono + REPLY_WAIT,
        };
    }

    /// True while asking.
    pub fn is_running(&self) -> bool {
        !matches!(self.state, QueryState::Idle)
    }

    /// Stops (the port closed).
    pub fn stop(&mut self) {
        self.state = QueryState::Idle;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.state {
            QueryState::Idle => None,
            QueryState::Quiet { until, give_up } => Some(until.min(give_up)),
            QueryState::Answer { until, .. } => Some(until),
        }
    }

    /// Time-driven steps.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> QueryProgress {
        let t = now.mono;
        match self.state {
            QueryState::Idle => QueryProgress::Working,
            QueryState::Quiet { until, give_up } if t >= until || t >= give_up => {
                port.flush_input();
                port.write(&[EXAMINE_VALUE, EXPANDED_ERROR]);
                self.state = QueryState::Answer {
                    until: t + REPLY_WAIT,
                    got: 0,
                    buf: [0; 2],
                };
                QueryProgress::Working
            }
            QueryState::Answer { until, .. } if t >= until => {
                self.state = QueryState::Idle;
                QueryProgress::Done(None)
            }
            _ => QueryProgress::Working,
        }
    }

    /// Bytes that arrived while asking.
    pub fn received(&mut self, bytes: &[u8], arrived: Now) -> QueryProgress {
        for &b in bytes {
            match &mut self.state {
                QueryState::Idle => {}
                QueryState::Quiet { until, .. } => *until = arrived.mono + QUIET,
                QueryState::Answer { got, buf, .. } => {
                    buf[*got] = b;
                    *got += 1;
                    if *got == 2 {
                        let code = *buf;
                        self.state = QueryState::Idle;
                        return QueryProgress::Done(Some(code));
                    }
                }
            }
        }
        QueryProgress::Working
    }
}
