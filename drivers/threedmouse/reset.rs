//! The 3D mouse's reset as a state machine over deadlines: `*R`, a pause while the control
//! unit restarts, then the diagnostics request `*` 05 (asked again while unanswered), whose
//! two-byte answer must report every self-test passed; then the filter count, if one is
//! configured. Pure code: bytes and times in, [`Progress`] and writes out.

use std::time::{Duration, Instant};

use crate::serial::PortOps;
use crate::time::Now;

/// The reset command.
pub const RESET: &[u8] = b"*R";
/// The diagnostics (status) request.
pub const DIAGNOSTICS: &[u8] = b"*\x05";
/// The prefix of the filter-count command; the count follows.
pub const FILTER_PREFIX: [u8; 4] = [0x2A, 0x24, 0x02, 0x07];
/// The diagnostics answer of a control unit whose tests all passed.
pub const ALL_PASSED: [u8; 2] = [0xBF, 0x3F];
/// Time the control unit is left alone after `*R` before it is asked for its diagnostics.
pub const SETTLE: Duration = Duration::from_millis(100);
/// Time a diagnostics request may go unanswered before it is sent again.
pub const STATUS_WAIT: Duration = Duration::from_millis(300);
/// Time from `*R` after which an unanswered reset has failed (C++ VRPN waits 4 s after `*R`,
/// then 1 s for the answer).
pub const GIVE_UP: Duration = Duration::from_secs(5);

/// The self-tests the diagnostics answer reports: (byte, bit, name).
pub const TESTS: [(usize, u8, &str); 7] = [
    (0, 0x01, "Control Unit test"),
    (0, 0x02, "Processor test"),
    (0, 0x04, "EPROM checksum test"),
    (0, 0x08, "RAM checksum test"),
    (0, 0x10, "Transmitter test"),
    (0, 0x20, "Receiver test"),
    (1, 0x01, "Serial Port test"),
];

/// What a reset step led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Waiting.
    Working,
    /// `*R` written.
    Started,
    /// The diagnostics answer reports every test passed; the reset is over. `rest` bytes
    /// of the read that brought it came after it.
    Done {
        /// Where the bytes after the answer start, in the read given to `received`.
        rest: usize,
    },
    /// No diagnostics answer within [`GIVE_UP`] of `*R`.
    NoAnswer,
    /// A diagnostics answer with failed tests (the two bytes).
    Failed([u8; 2]),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    /// `*R` sent; nothing is asked before `until`.
    Settling {
        until: Instant,
    },
    /// Diagnostics asked; `got` bytes of the answer so far; asked again at `again`.
    Asking {
        again: Instant,
        answer: [u8; 2],
        got: usize,
    },
}

/// The reset's progress. See the module documentation.
#[derive(Debug)]
pub struct ResetSequence {
    filter: u8,
    step: Step,
    started: Option<Instant>,
    asked: u32,
}

impl ResetSequence {
    /// A reset that ends by setting the filter count `filter` (1: the device's default, not
    /// sent).
    pub fn new(filter: u8) -> ResetSequence {
        ResetSequence {
            filter,
            step: Step::Idle,
            started: None,
            asked: 0,
        }
    }

    /// Diagnostics requests written in the current attempt.
    pub fn asked(&self) -> u32 {
        self.asked
    }

    /// Writes `*R` and waits.
    pub fn start(&mut self, now: Now, port: &mut PortOps) -> Progress {
        port.flush_input();
        port.write(RESET);
        self.started = Some(now.mono);
        self.asked = 0;
        self.step = Step::Settling {
            until: now.mono + SETTLE,
        };
        Progress::Started
    }

    /// Bytes that arrived.
    pub fn received(&mut self, bytes: &[u8], port: &mut PortOps) -> Progress {
        let Step::Asking {
            again,
            mut answer,
            mut got,
        } = self.step
        else {
            // Before the question, bytes are what the unit said while restarting: dropped
            // (as C++ VRPN drops them).
            return Progress::Working;
        };
        for (i, &b) in bytes.iter().enumerate() {
            answer[got] = b;
            got += 1;
            if got == answer.len() {
                self.step = Step::Idle;
                if !passed(answer) {
                    return Progress::Failed(answer);
                }
                if self.filter > 1 {
                    port.write(&filter_command(self.filter));
                }
                return Progress::Done { rest: i + 1 };
            }
        }
        self.step = Step::Asking { again, answer, got };
        Progress::Working
    }

    /// The deadline passed: ask (again), or give up.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        let due = match self.step {
            Step::Idle => return Progress::Working,
            Step::Settling { until } => until,
            Step::Asking { again, .. } => again,
        };
        if now.mono < due {
            return Progress::Working;
        }
        let give_up = self.started.unwrap_or(now.mono) + GIVE_UP;
        if now.mono >= give_up {
            self.step = Step::Idle;
            return Progress::NoAnswer;
        }
        // A late half answer to the previous request is dropped with it.
        port.flush_input();
        port.write(DIAGNOSTICS);
        self.asked += 1;
        self.step = Step::Asking {
            again: (now.mono + STATUS_WAIT).min(give_up),
            answer: [0; 2],
            got: 0,
        };
        Progress::Working
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.step {
            Step::Idle => None,
            Step::Settling { until } => Some(until),
            Step::Asking { again, .. } => Some(again),
        }
    }

    /// Forgets the attempt.
    pub fn stop(&mut self) {
        self.step = Step::Idle;
        self.started = None;
    }
}

/// Whether a diagnostics answer reports every test passed (the bits C++ VRPN checks).
pub fn passed(answer: [u8; 2]) -> bool {
    TESTS.iter().all(|&(i, bit, _)| answer[i] & bit != 0)
}

/// The names of the tests a diagnostics answer reports failed.
pub fn failed_tests(answer: [u8; 2]) -> impl Iterator<Item = &'static str> {
    TESTS
        .iter()
        .filter(move |&&(i, bit, _)| answer[i] & bit == 0)
        .map(|&(_, _, name)| name)
}

/// The command setting the filter count to `n`.
pub fn filter_command(n: u8) -> [u8; 5] {
    let [a, b, c, d] = FILTER_PREFIX;
    [a, b, c, d, n]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::serial::PortOp;
    use crate::TimeVal;

    fn now(t0: Instant, ms: u64) -> Now {
        Now {
            mono: t0 + Duration::from_millis(ms),
            wall: TimeVal::new(1_700_000_000, 0).plus_secs(ms as f64 / 1e3),
        }
    }

    fn writes(port: &mut PortOps) -> Vec<Vec<u8>> {
        let w = port
            .ops()
            .iter()
            .filter_map(|op| match *op {
                PortOp::Write { start, len } => Some(port.write_bytes(start, len).to_vec()),
                _ => None,
            })
            .collect();
        port.clear();
        w
    }

    #[test]
    fn reset_asks_after_settling_and_sets_the_filter() {
        let t0 = Instant::now();
        let mut port = PortOps::new();
        let mut r = ResetSequence::new(3);
        assert_eq!(r.start(now(t0, 0), &mut port), Progress::Started);
        assert_eq!(writes(&mut port), vec![RESET.to_vec()]);
        assert_eq!(r.deadline(), Some(t0 + SETTLE));
        // Chatter while restarting is dropped.
        assert_eq!(r.received(&[0xBF, 0x3F], &mut port), Progress::Working);
        assert_eq!(r.poll(now(t0, 99), &mut port), Progress::Working);
        assert!(writes(&mut port).is_empty());
        assert_eq!(r.poll(now(t0, 100), &mut port), Progress::Working);
        assert_eq!(writes(&mut port), vec![DIAGNOSTICS.to_vec()]);
        // Unanswered: asked again.
        assert_eq!(r.poll(now(t0, 400), &mut port), Progress::Working);
        assert_eq!(writes(&mut port), vec![DIAGNOSTICS.to_vec()]);
        assert_eq!(r.asked(), 2);
        assert_eq!(r.received(&[0xBF], &mut port), Progress::Working);
        assert_eq!(
            r.received(&[0x3F, 0x80, 0x01], &mut port),
            Progress::Done { rest: 1 }
        );
        assert_eq!(writes(&mut port), vec![vec![0x2A, 0x24, 0x02, 0x07, 3]]);
        assert_eq!(r.deadline(), None);
    }

    #[test]
    fn failed_tests_and_silence_fail_the_attempt() {
        let t0 = Instant::now();
        let mut port = PortOps::new();
        let mut r = ResetSequence::new(1);
        r.start(now(t0, 0), &mut port);
        r.poll(now(t0, 100), &mut port);
        assert_eq!(
            r.received(&[0x9F, 0x3F], &mut port),
            Progress::Failed([0x9F, 0x3F])
        );
        assert_eq!(
            failed_tests([0x9F, 0x3E]).collect::<Vec<_>>(),
            ["Receiver test", "Serial Port test"]
        );
        assert!(passed(ALL_PASSED));
        r.start(now(t0, 1000), &mut port);
        let mut t = 1000;
        let mut last = Progress::Working;
        while t < 7000 && last == Progress::Working {
            t = r.deadline().map(|d| (d - t0).as_millis() as u64).unwrap();
            last = r.poll(now(t0, t), &mut port);
        }
        assert_eq!(last, Progress::NoAnswer);
        assert_eq!(t, 1000 + GIVE_UP.as_millis() as u64);
        // Filter 1 writes nothing after the answer.
        let mut r = ResetSequence::new(1);
        r.start(now(t0, 0), &mut port);
        r.poll(now(t0, 100), &mut port);
        writes(&mut port);
        assert_eq!(
            r.received(&ALL_PASSED, &mut port),
            Progress::Done { rest: 2 }
        );
        assert!(writes(&mut port).is_empty());
    }
}
