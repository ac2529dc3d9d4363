//! The clock and position of a log replay, free of I/O and of dispatch.
//!
//! A [`Replay`] reads a log through a window of bounded size (whatever the file's size) and
//! decides which entry plays next; the connection core feeds each played entry through the
//! same id-translation path as a live peer's message.
//! The clock follows C++ `vrpn_File_Connection`: the first pass after open or reset only arms
//! the wall clock; later passes accumulate `elapsed × rate` and play every entry whose time is
//! at or before `file time + accumulated`, leaving the original timestamps untouched.

use std::time::Instant;

use super::cursor::Cursor;
use super::format::{EntryHeader, LogEntry, ENTRY_HEADER_LEN};
use super::reader::{LogError, LogReader};
use crate::time::TimeVal;
use crate::wire::COOKIE_LEN;

/// What the next [`Replay::next_due`] call may play.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    /// Nothing is due.
    Idle,
    /// The leading system entries (descriptions) at open and after a reset.
    Leading,
    /// Every entry with a time at or before the target, then file time = target.
    Until(TimeVal),
    /// Exactly the next entry, whatever its time.
    One,
}

/// One entry to play: its header and where its payload lies in the file.
#[derive(Clone, Copy, Debug)]
pub struct DueEntry {
    /// The entry's header (ids are the log's ids).
    pub header: EntryHeader,
    /// File offset of the payload ([`Replay::payload`] gives its bytes).
    pub payload_at: usize,
}

/// Replay position, clock and controls over one log.
#[derive(Debug)]
pub struct Replay {
    reader: LogReader,
    /// The window the replay reads through (allocated at open: playing allocates nothing).
    cursor: Cursor,
    next: usize,
    file_time: TimeVal,
    start_time: TimeVal,
    accum: f64,
    last_wall: Option<Instant>,
    rate: f64,
    mode: Mode,
    eof: bool,
    error: Option<LogError>,
    error_taken: bool,
    lowest: Option<TimeVal>,
    highest: Option<TimeVal>,
    /// Set by a reset: the connection reports it as a dropped-connection event.
    reset_pending: bool,
}

impl Replay {
    /// Opens `path` (a regular file; the cookie is checked first) and scans it once for its
    /// user-message time range, reading through a window of bounded size.
    pub fn open(path: &str) -> Result<Replay, LogError> {
        Ok(Replay::from_reader(LogReader::open(path)?))
    }

    /// A replay of an opened log.
    pub fn from_reader(reader: LogReader) -> Replay {
        let mut lowest: Option<TimeVal> = None;
        let mut highest: Option<TimeVal> = None;
        let mut first_user = None;
        let mut first_time = None;
        let mut entries = reader.entries();
        while let Some(Ok(e)) = entries.next_entry() {
            first_time.get_or_insert(e.time());
            if e.type_id() >= 0 {
                let t = e.time();
                first_user.get_or_insert(t);
                lowest = Some(lowest.map_or(t, |l| l.min(t)));
                highest = Some(highest.map_or(t, |h| h.max(t)));
            }
        }
        drop(entries);
        let start_time = first_user.or(first_time).unwrap_or(TimeVal::ZERO);
        Replay {
            reader,
            cursor: Cursor::with_window(),
            next: COOKIE_LEN,
            file_time: start_time,
            start_time,
            accum: 0.0,
            last_wall: None,
            rate: 1.0,
            mode: Mode::Leading,
            eof: false,
            error: None,
            error_taken: false,
            lowest,
            highest,
            reset_pending: false,
        }
    }

    /// The payload of the entry [`next_due`](Self::next_due) returned last (empty if another
    /// read came in between).
    pub fn payload(&self, due: &DueEntry) -> &[u8] {
        self.cursor
            .held(
                self.reader.source(),
                due.payload_at,
                due.header.payload_len as usize,
            )
            .unwrap_or(&[])
    }

    /// The cookie of the log.
    pub fn cookie_bytes(&self) -> &[u8; COOKIE_LEN] {
        self.reader.cookie_bytes()
    }

    /// Path of the log.
    pub fn path(&self) -> &std::path::Path {
        self.reader.path()
    }

    /// Advances the clock; call once per mainloop pass.
    pub fn tick(&mut self, now: Instant) {
        if self.mode == Mode::Leading {
            return;
        }
        let Some(last) = self.last_wall.replace(now) else {
            return; // first pass after open or reset: arm the clock, play nothing
        };
        self.accumulate(now.duration_since(last));
        let target = self.file_time.plus_secs(self.accum);
        if self.peek_time().is_some_and(|t| t < target) {
            self.accum = 0.0;
            self.mode = Mode::Until(target);
        }
    }

    fn peek_time(&mut self) -> Option<TimeVal> {
        match self.cursor.entry_at(self.reader.source(), self.next) {
            Ok(Some(e)) => Some(e.time()),
            _ => None,
        }
    }

    /// The entry at the current position, or the end (`None`, with the damage kept).
    fn current(&mut self) -> Option<LogEntry<'_>> {
        match self.cursor.entry_at(self.reader.source(), self.next) {
            Ok(Some(e)) => Some(e),
            Ok(None) => None,
            Err(e) => {
                self.error = Some(LogError::from_cursor(self.reader.path(), self.next, e));
                None
            }
        }
    }

    /// The next entry that is due now, if any. Advances the position and the file time.
    pub fn next_due(&mut self) -> Option<DueEntry> {
        if self.eof || self.mode == Mode::Idle {
            return None;
        }
        let Some(entry) = self.current() else {
            self.finish_mode();
            self.eof = true;
            return None;
        };
        let (header, end) = (entry.header, entry.end_offset());
        let due = match self.mode {
            Mode::Idle => false,
            Mode::Leading => header.type_id < 0,
            Mode::Until(t) => header.time() <= t,
            Mode::One => true,
        };
        if !due {
            self.finish_mode();
            return None;
        }
        if self.mode == Mode::One {
            self.mode = Mode::Idle;
        }
        let payload_at = self.next + ENTRY_HEADER_LEN;
        self.next = end;
        self.file_time = header.time();
        Some(DueEntry { header, payload_at })
    }

    fn finish_mode(&mut self) {
        match self.mode {
            Mode::Until(t) => self.file_time = t,
            Mode::Leading => self.file_time = self.start_time,
            _ => {}
        }
        self.mode = Mode::Idle;
    }

    /// The damage that ended the replay early, once (file, offset, problem).
    pub fn take_error(&mut self) -> Option<&LogError> {
        if self.error.is_some() && !self.error_taken {
            self.error_taken = true;
            self.error.as_ref()
        } else {
            None
        }
    }

    /// True when every whole entry has been played.
    pub fn eof(&self) -> bool {
        self.eof
    }

    /// Sets the speed at `now` (the caller's clock): 1 real time, 0 paused, 10 ten times
    /// faster, `f64::INFINITY` as fast as possible. Time so far is accumulated at the old rate.
    pub fn set_rate(&mut self, rate: f64, now: Instant) {
        if let Some(last) = self.last_wall {
            self.accumulate(now.duration_since(last));
            self.last_wall = Some(now);
        }
        self.rate = if rate.is_nan() { 0.0 } else { rate.max(0.0) };
    }

    /// Adds `elapsed` wall time at the current rate to the file time still to play. (No time
    /// adds nothing, even at an infinite rate, where the product would be NaN and stall the
    /// replay for good.)
    fn accumulate(&mut self, elapsed: std::time::Duration) {
        if !elapsed.is_zero() && self.rate > 0.0 {
            self.accum += elapsed.as_secs_f64() * self.rate;
        }
    }

    /// The speed factor.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Back to the start: leading descriptions replay on the next pass, the clock re-arms.
    pub fn reset(&mut self) {
        self.next = COOKIE_LEN;
        self.file_time = self.start_time;
        self.accum = 0.0;
        self.last_wall = None;
        self.mode = Mode::Leading;
        self.eof = false;
        self.reset_pending = true;
    }

    /// True once after each reset (the connection fires a dropped-connection event).
    pub fn take_reset(&mut self) -> bool {
        std::mem::take(&mut self.reset_pending)
    }

    /// Plays the leading system entries now (after open or reset).
    pub fn play_leading(&mut self) {
        if self.mode == Mode::Leading {
            return;
        }
        self.mode = Mode::Leading;
    }

    /// Asks to play every entry up to `elapsed` seconds after the first message; rewinds first
    /// when that is before the current file time. The target saturates at the ends of
    /// [`TimeVal`]'s range (`f64::INFINITY` plays to the end); NaN asks for nothing.
    pub fn play_to_time(&mut self, elapsed: f64) {
        if elapsed.is_nan() {
            return;
        }
        let target = self.base_time().plus_secs(elapsed);
        if target < self.file_time {
            self.reset();
        }
        self.last_wall = None;
        self.mode = Mode::Until(target);
    }

    /// Asks to play exactly the next entry (stepping, or "as fast as the caller loops").
    pub fn play_one(&mut self) {
        self.mode = Mode::One;
    }

    /// Moves to `elapsed` seconds after the first message without delivering user messages;
    /// the connection feeds the system entries passed over through its id tables, so descriptions
    /// are not lost (C++ loses them). Returns whether the target lies within the log. The
    /// target saturates at the ends of [`TimeVal`]'s range (`f64::INFINITY` goes to the end
    /// and returns false); NaN is refused (false, nothing moves).
    pub fn jump_to_time(&mut self, elapsed: f64) -> bool {
        if elapsed.is_nan() {
            return false;
        }
        let target = self.base_time().plus_secs(elapsed);
        if target < self.file_time || self.eof {
            self.reset();
            self.reset_pending = false;
        }
        self.mode = Mode::Until(target);
        self.last_wall = None;
        self.highest.is_some_and(|h| target <= h)
    }

    /// File time now: where the replay stands on the log's own time axis.
    pub fn file_time(&self) -> TimeVal {
        self.file_time
    }

    /// Seconds since the first message (the base of `play_to_time` and `jump_to_time`).
    pub fn elapsed(&self) -> f64 {
        self.file_time.seconds_since(self.base_time())
    }

    fn base_time(&self) -> TimeVal {
        self.lowest.unwrap_or(self.start_time)
    }

    /// Time of the earliest user message.
    pub fn first_time(&self) -> Option<TimeVal> {
        self.lowest
    }

    /// Time of the latest user message.
    pub fn last_time(&self) -> Option<TimeVal> {
        self.highest
    }

    /// Seconds between the first and the last user message.
    pub fn length_secs(&self) -> f64 {
        match (self.lowest, self.highest) {
            (Some(l), Some(h)) => h.seconds_since(l),
            _ => 0.0,
        }
    }

    /// True while entries remain due in this pass.
    pub fn busy(&self) -> bool {
        self.mode != Mode::Idle && !self.eof
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::format::encode_entry;
    use crate::wire::Cookie;

    /// A log of `n` user messages 10 ms apart.
    fn log(n: i64) -> LogReader {
        let mut file = Cookie::ours(0).to_bytes().to_vec();
        let mut buf = [0u8; 64];
        for i in 0..n {
            let t = TimeVal::new(100, 0).plus_secs(i as f64 * 0.01);
            let len = encode_entry(&mut buf, 0, 0, t, &[i as u8; 4]).unwrap();
            file.extend_from_slice(&buf[..len]);
        }
        LogReader::from_bytes(file, "mem.vrpn").unwrap()
    }

    fn drain(r: &mut Replay) -> usize {
        std::iter::from_fn(|| r.next_due()).count()
    }

    #[test]
    fn an_infinite_rate_and_no_time_passing_do_not_stall_the_clock() {
        let mut r = Replay::from_reader(log(10));
        assert_eq!(drain(&mut r), 0, "no leading system entries");
        let t0 = Instant::now();
        r.tick(t0); // arms the clock
        r.set_rate(f64::INFINITY, t0);
        r.tick(t0); // no time passed: ∞ × 0 must not poison the clock
        assert_eq!(drain(&mut r), 0);
        r.tick(t0 + std::time::Duration::from_millis(1));
        assert_eq!(drain(&mut r), 10);
    }
}
