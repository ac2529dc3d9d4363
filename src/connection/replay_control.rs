//! Controls of a log replay (C++ `vrpn_File_Connection`): rate, reset, play-to and jump-to
//! (elapsed or absolute file times), bookmarks, a cap per pass, and the `vrpn_File_Controller`
//! messages that control a replay from elsewhere.
//!
//! Every control may be called from inside a callback, including one the replay itself is
//! running: the control changes the replay's position at once, and what it plays is
//! delivered when the callback returns, by the delivery loop that ran the callback.

use super::{Connection, Core};
use crate::log::replay::{Bookmark, Replay};
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

/// Absolute file times, bookmarks and a cap on what one pass plays.
impl ReplayControl<'_> {
    /// Plays, now, every message up to the file time `target` (the log's own timestamps;
    /// C++ `play_to_filetime`), rewinding first when that is behind the current position.
    pub fn play_to_filetime(&self, target: TimeVal) {
        self.conn.skip_user_messages(false);
        self.conn.with_replay(|r| r.play_to_filetime(target));
        self.conn.play_due();
    }

    /// Moves to the file time `target` without delivering the messages in between
    /// (descriptions on the way are still learned; C++ `jump_to_filetime`). Returns whether
    /// that time is in the log.
    pub fn jump_to_filetime(&self, target: TimeVal) -> bool {
        let inside = self.conn.with_replay(|r| r.jump_to_filetime(target));
        self.conn.skip_user_messages(true);
        self.conn.play_due();
        inside
    }

    /// The position now, to come back to with [`go_to_bookmark`](Self::go_to_bookmark).
    pub fn bookmark(&self) -> Bookmark {
        self.conn.with_replay(|r| r.bookmark())
    }

    /// Moves to `bookmark` without delivering the messages in between: the next message
    /// played is the one that was next when the bookmark was taken. Returns false (and moves
    /// nothing) for a bookmark beyond the end of this log (one taken on a longer log).
    pub fn go_to_bookmark(&self, bookmark: Bookmark) -> bool {
        let ok = self.conn.with_replay(|r| r.go_to_bookmark(bookmark));
        if ok {
            self.conn.skip_user_messages(true);
            self.conn.play_due();
        }
        ok
    }

    /// Plays at most `max` messages per `mainloop()` or control call (0: no limit; C++
    /// `limit_messages_played_back`): a pass that reaches it stops at the last message played
    /// and later passes go on from there (frame by frame through a fast stream).
    pub fn limit_messages_played_back(&self, max: u32) {
        self.conn.with_replay(|r| r.limit_messages_played_back(max));
    }

    /// The limit [`limit_messages_played_back`](Self::limit_messages_played_back) set.
    pub fn messages_limit(&self) -> u32 {
        self.conn.with_replay(|r| r.messages_limit())
    }
}

impl Connection {
    /// A replay obeys `vrpn_File_Controller` messages packed on it (C++ `vrpn_File_Connection`
    /// does): from a [`FileController`] on the same connection, or, through a relay that
    /// re-serves the replay, from clients over the network.
    pub(crate) fn serve_file_controller(&self) -> Result<(), crate::Error> {
        use crate::dispatch::SenderFilter;
        use crate::wire::payload::file_controller as codec;
        let ids = FileControllerIds::register(self)?;
        let only = SenderFilter::Only(ids.sender);
        self.register_handler(ids.set_replay_rate, only, |m| {
            if let (Ok(rate), Some(r)) = (codec::decode_rate(m.payload), m.connection().replay()) {
                r.set_rate(f64::from(rate));
            }
        });
        self.register_handler(ids.reset, only, |m| {
            if let Some(r) = m.connection().replay() {
                r.reset();
            }
        });
        self.register_handler(ids.play_to_time, only, |m| {
            if let (Ok(t), Some(r)) = (
                codec::decode_play_to_time(m.payload),
                m.connection().replay(),
            ) {
                r.play_to_time(t.as_secs_f64());
            }
        });
        Ok(())
    }
}

/// The sender and types of `vrpn_File_Controller` on one connection.
#[derive(Clone, Copy, Debug)]
pub struct FileControllerIds {
    /// `vrpn File Controller`.
    pub sender: crate::dispatch::SenderId,
    /// `vrpn_File set_replay_rate`.
    pub set_replay_rate: crate::dispatch::TypeId,
    /// `vrpn_File reset`.
    pub reset: crate::dispatch::TypeId,
    /// `vrpn_File play_to_time`.
    pub play_to_time: crate::dispatch::TypeId,
}

impl FileControllerIds {
    /// Registers the sender and the three types in C++ order.
    pub fn register(conn: &Connection) -> Result<FileControllerIds, crate::Error> {
        use crate::wire::payload::file_controller as codec;
        Ok(FileControllerIds {
            sender: conn.register_sender(codec::SENDER)?,
            set_replay_rate: conn.register_type(codec::SET_REPLAY_RATE)?,
            reset: conn.register_type(codec::RESET)?,
            play_to_time: conn.register_type(codec::PLAY_TO_TIME)?,
        })
    }
}

/// Controls a log replay by messages (C++ `vrpn_File_Controller`): on a replay connection it
/// acts on the replay directly; on a client connection to a server that re-serves a replay
/// (`vrpn_Relay Device@file:LOG`), it controls that replay over the network. A C++
/// `vrpn_File_Controller` works the same way against such a server. On a replay connection a
/// control takes effect in the next `mainloop()` (which delivers the message to the replay).
pub struct FileController {
    conn: Connection,
    ids: FileControllerIds,
}

impl FileController {
    /// A controller on `conn`.
    pub fn new(conn: &Connection) -> Result<FileController, crate::Error> {
        Ok(FileController {
            conn: conn.clone(),
            ids: FileControllerIds::register(conn)?,
        })
    }

    /// Sets the replay rate (1 real time, 0 paused, 2 twice as fast).
    pub fn set_replay_rate(&self, rate: f32) -> Result<(), crate::Error> {
        use crate::wire::payload::file_controller as codec;
        let mut buf = [0u8; codec::RATE_LEN];
        let n = codec::encode_rate(&mut buf, rate);
        self.send(self.ids.set_replay_rate, &buf[..n])
    }

    /// Back to the start of the log (the rate is kept).
    pub fn reset(&self) -> Result<(), crate::Error> {
        self.send(self.ids.reset, &[])
    }

    /// Plays everything up to `elapsed` after the first message of the log.
    pub fn play_to_time(&self, elapsed: TimeVal) -> Result<(), crate::Error> {
        use crate::wire::payload::file_controller as codec;
        let mut buf = [0u8; codec::PLAY_TO_TIME_LEN];
        let n = codec::encode_play_to_time(&mut buf, elapsed);
        self.send(self.ids.play_to_time, &buf[..n])
    }

    fn send(&self, type_id: crate::dispatch::TypeId, payload: &[u8]) -> Result<(), crate::Error> {
        self.conn.pack_message(
            self.conn.now().wall,
            type_id,
            self.ids.sender,
            payload,
            crate::wire::class::RELIABLE,
        )
    }
}
