//! When each logged record's first byte was actually handed to the line.
//!
//! A simulator that paces its bytes at the line's baud rate queues a record's bytes with the
//! times they are due; they leave later, in whichever step of the simulator finds them due
//! (on a pseudo-terminal: [`PtyDevice::step`](super::PtyDevice::step), which writes them at
//! once). A record's *scheduled* first byte is known when it is queued; the time its first
//! byte was *written* is known only when that byte leaves. [`FirstWrites`] counts the bytes
//! queued and handed out, and stamps every logged record whose first byte leaves in a step
//! with that step's `now`: what a timing measurement must compare a driver's stamp with
//! (the second record of a frame leaves a whole record's transmission after the first).
//!
//! No allocation: two counters and a cursor into the simulator's own log.

use crate::time::Now;

/// A logged record that [`FirstWrites`] can stamp.
pub trait FirstByteLogged {
    /// Offset of its first byte in everything the simulator queued (from
    /// [`FirstWrites::queue`]).
    fn first_offset(&self) -> u64;
    /// Its first byte was handed to the line at `at`.
    fn set_written(&mut self, at: Now);
}

/// Byte counts of a simulator's paced output. See the module documentation.
#[derive(Clone, Debug, Default)]
pub struct FirstWrites {
    queued: u64,
    handed: u64,
    /// The first log entry not yet stamped (or passed over as never sent).
    next: usize,
}

impl FirstWrites {
    /// Counts nothing yet.
    pub fn new() -> FirstWrites {
        FirstWrites::default()
    }

    /// `n` bytes join the output queue; returns the stream offset of the first of them.
    pub fn queue(&mut self, n: usize) -> u64 {
        let first = self.queued;
        self.queued += n as u64;
        first
    }

    /// `n` bytes leave the queue: handed to the line at `now`, or lost (`None`: a muted
    /// device). Every entry of `log` whose first byte is among them gets `now` (a lost one
    /// gets nothing and is passed over).
    pub fn hand<R: FirstByteLogged>(&mut self, n: usize, now: Option<Now>, log: &mut [R]) {
        if n == 0 {
            return;
        }
        self.handed += n as u64;
        while let Some(r) = log.get_mut(self.next) {
            if r.first_offset() >= self.handed {
                break;
            }
            if let Some(now) = now {
                r.set_written(now);
            }
            self.next += 1;
        }
    }

    /// The simulator emptied its log: stamping starts again at its first entry.
    pub fn log_cleared(&mut self) {
        self.next = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeVal;
    use std::time::{Duration, Instant};

    #[derive(Debug)]
    struct Rec(u64, Option<Now>);

    impl FirstByteLogged for Rec {
        fn first_offset(&self) -> u64 {
            self.0
        }
        fn set_written(&mut self, at: Now) {
            self.1 = Some(at);
        }
    }

    fn at(us: u64) -> Now {
        Now {
            mono: Instant::now() + Duration::from_micros(us),
            wall: TimeVal::new(1, us as i64),
        }
    }

    #[test]
    fn each_record_gets_the_step_that_hands_out_its_first_byte() {
        let mut w = FirstWrites::new();
        let mut log = Vec::new();
        // A frame of two 10-byte records; a 5-byte answer in between that is not logged.
        log.push(Rec(w.queue(10), None));
        w.queue(5);
        log.push(Rec(w.queue(10), None));
        let (t1, t2, t3, t4) = (at(1), at(2), at(3), at(4));
        w.hand(4, Some(t1), &mut log);
        assert_eq!(log[0].1, Some(t1));
        w.hand(11, Some(t2), &mut log); // bytes 4..15: the rest of record 0 and the answer
        assert_eq!(log[1].1, None);
        w.hand(1, Some(t3), &mut log); // byte 15: record 1's first
        assert_eq!(log[0].1, Some(t1), "never stamped twice");
        assert_eq!(log[1].1, Some(t3));
        // Lost bytes stamp nothing, and the next record is stamped when its turn comes.
        log.push(Rec(w.queue(10), None));
        log.push(Rec(w.queue(10), None));
        w.hand(12, None, &mut log);
        assert_eq!(log[2].1, None);
        w.hand(7, Some(t4), &mut log);
        assert_eq!(log[3].1, None, "record 3 starts at byte 35, not yet handed");
        w.hand(0, Some(t4), &mut log);
        w.hand(1, Some(t4), &mut log);
        assert_eq!(log[3].1, Some(t4));
        // A cleared log stamps its new entries (9 bytes of record 3 are still queued).
        log.clear();
        w.log_cleared();
        log.push(Rec(w.queue(3), None));
        w.hand(9, Some(t2), &mut log);
        assert_eq!(log[0].1, None);
        w.hand(1, Some(t1), &mut log);
        assert_eq!(log[0].1, Some(t1));
    }
}
