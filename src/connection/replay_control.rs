//! Controls of a log replay (C++ `vrpn_File_Connection`): rate, reset, play-to, jump-to.
//!
//! Every control may be called from inside a callback, including one the replay itself is
//! running: the control changes the replay's position at once, and what it plays is
//! delivered when the callback returns, by the delivery loop that ran the callback.

use super::{Connection, Core};
use crate::log::replay::Replay;
use crate::time::TimeVal;

/// Controls of a log replay, borrowed from its connection.
pub struct ReplayControl<'a> {
    pub(super) conn: &'a Connection,
}

impl Connection {
    /// Replay controls, when this connection replays a log file.
    pub fn replay(&self) -> Option<ReplayControl<'_>> {
        self.is_replay().then_some(ReplayControl { conn: self })
    }

    /// True when this connection replays a log file.
    pub fn is_replay(&self) -> bool {
        self.inner.core.borrow_mut().session.replay_mut().is_some()
    }

    fn with_replay<T>(&self, f: impl FnOnce(&mut Replay) -> T) -> T {
        let mut core = self.inner.core.borrow_mut();
        let Core { session, .. } = &mut *core;
        f(session.replay_mut().expect("a replay connection"))
    }

    /// Delivers what the replay has due now. Called from inside a callback (the payload
    /// buffer is then on loan to the running delivery), it delivers nothing itself: the
    /// control has changed the replay's position, and the delivery loop that runs the
    /// callback plays what became due as soon as the callback returns (the next
    /// `mainloop()` when no delivery loop runs it).
    fn play_due(&self) {
        if self.inner.depth.get() > 0 {
            return;
        }
        let clock = &self.inner.clock;
        let outer = clock.begin();
        // Everything due, however long it takes: the control promises it (an interruption
        // asked for by a callback still ends it early).
        crate::net::clear_interrupt();
        self.pump(clock, &mut crate::net::PassBudget::new(None));
        if outer {
            clock.end();
        }
    }

    /// Starts or ends skipping: user messages due meanwhile are consumed without being
    /// delivered (descriptions on the way are still learned).
    fn skip_user_messages(&self, skip: bool) {
        self.inner
            .core
            .borrow_mut()
            .session
            .set_replay_skipping(skip);
    }
}

impl ReplayControl<'_> {
    /// Sets the speed: 1.0 real time, 0 paused, 10 ten times faster, `f64::INFINITY` as
    /// fast as possible.
    pub fn set_rate(&self, rate: f64) {
        let now = self.conn.now().mono;
        self.conn.with_replay(|r| r.set_rate(rate, now));
    }

    /// The speed factor.
    pub fn rate(&self) -> f64 {
        self.conn.with_replay(|r| r.rate())
    }

    /// Back to the start (handlers see a dropped-connection event, as in C++).
    pub fn reset(&self) {
        self.conn.skip_user_messages(false);
        self.conn.with_replay(|r| r.reset());
        self.conn.play_due();
    }

    /// Plays, now, every message up to `secs` after the first one (rewinding first when that
    /// is behind the current position). Saturates: `f64::INFINITY` plays to the end; NaN does
    /// nothing. From inside a callback: when the callback returns.
    pub fn play_to_time(&self, secs: f64) {
        self.conn.skip_user_messages(false);
        self.conn.with_replay(|r| r.play_to_time(secs));
        self.conn.play_due();
    }

    /// Plays the next message now, whatever its time (from inside a callback: when the
    /// callback returns). Returns false at the end of the file.
    pub fn play_one(&self) -> bool {
        if self.eof() {
            return false;
        }
        self.conn.skip_user_messages(false);
        self.conn.with_replay(|r| r.play_one());
        self.conn.play_due();
        true
    }

    /// Moves to `secs` after the first message without delivering the messages in between
    /// (descriptions on the way are still learned). Returns whether that time is in the log:
    /// a time past the end (`f64::INFINITY` included) moves to the end and returns false; NaN
    /// returns false and moves nothing.
    pub fn jump_to_time(&self, secs: f64) -> bool {
        let inside = self.conn.with_replay(|r| r.jump_to_time(secs));
        self.conn.skip_user_messages(true);
        self.conn.play_due();
        inside
    }

    /// True when every message has been played.
    pub fn eof(&self) -> bool {
        self.conn.with_replay(|r| r.eof())
    }

    /// Where the replay stands, on the log's own clock.
    pub fn file_time(&self) -> TimeVal {
        self.conn.with_replay(|r| r.file_time())
    }

    /// Seconds since the first message.
    pub fn elapsed(&self) -> f64 {
        self.conn.with_replay(|r| r.elapsed())
    }

    /// Time of the first user message.
    pub fn first_time(&self) -> Option<TimeVal> {
        self.conn.with_replay(|r| r.first_time())
    }

    /// Time of the last user message.
    pub fn last_time(&self) -> Option<TimeVal> {
        self.conn.with_replay(|r| r.last_time())
    }

    /// Seconds between the first and last user messages.
    pub fn length_secs(&self) -> f64 {
        self.conn.with_replay(|r| r.length_secs())
    }
}
