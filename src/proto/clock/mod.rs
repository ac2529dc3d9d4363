//! Clock synchronisation between two peers: a pure, allocation-free state machine per peer that
//! decides when to send a [`Query`], turns each [`Reply`] into an offset sample, and estimates
//! the offset between the peer's clock and ours with a bound that holds.
//!
//! Nothing here reads a clock or touches a socket: the caller passes a [`Now`] into every call,
//! sends the queries [`ClockSync::poll_query`] returns, wakes up at
//! [`ClockSync::next_deadline`], and hands every decoded reply to [`ClockSync::handle_reply`].
//! The responder's side is [`Reply::answer`].
//!
//! # Offset and bound
//!
//! The *offset* is `peer clock − local clock` (both wall clocks, read at the same instant), so
//! `local = remote − offset`; [`ClockSync::remote_to_local`] applies it.
//!
//! One exchange gives, from NTP's four timestamps (`t1` query sent and `t4` reply received on
//! the local clock; `t2` query received and `t3` reply sent on the peer's):
//!
//! ```text
//! offset     = ((t2 − t1) + (t3 − t4)) / 2
//! round trip =  (t4 − t1) − (t3 − t2)
//! ```
//!
//! If the query takes `a ≥ 0` to travel and the reply `b ≥ 0`, the measured offset is the true
//! one plus `(a − b) / 2` and the round trip is `a + b`, so the true offset is within half the
//! round trip of the measurement — whatever the asymmetry. Each sample's *radius* adds what the
//! arithmetic cannot see: the microsecond rounding of the four timestamps (2 µs in all) and the
//! two clocks drifting apart during the exchange (at most `max_skew_ppm` × `t4 − t1`).
//! `t4 − t1` is measured on the monotonic clock, so a local wall-clock step during an exchange
//! does not corrupt the sample.
//!
//! Over a long session the offset moves: the clocks run at slightly different rates (the
//! *drift*, tens of ppm for ordinary crystals). The estimator keeps the best exchange of each of
//! the last `window` rounds. Assuming the drift is constant over that window, every pair of kept
//! samples bounds it: `(θk ± rk) − (θj ± rj)` over `tk − tj`. Intersecting all pairs with
//! `±max_skew_ppm` gives an interval that must contain the true drift; the estimate uses its
//! middle, and its half-width (plus `wander_ppm` for rates that change) is the *drift error*.
//! Then, for any kept sample `s`,
//!
//! ```text
//! offset(t)      = θs + drift × (t − ts)
//! uncertainty(t) = rs + drift error × |t − ts|
//! ```
//!
//! holds, because both `θs ± rs` and the drift interval contain the truth. The estimate rests on
//! the sample that makes this uncertainty smallest — NTP's clock filter, where the lowest round
//! trip wins unless it is old enough for the drift error to outweigh it. Since every sample's
//! uncertainty grows at the same rate, that choice only changes when a sample arrives.
//!
//! The bound assumes that `t1`/`t3` are read no later than the bytes are written, `t2`/`t4` no
//! earlier than they are read, each clock's drift is within `max_skew_ppm` and changes by less
//! than `wander_ppm` over the window.
//!
//! # Rounds
//!
//! When a connection comes up, a *quick* round sends `quick_queries` queries `quick_spacing`
//! apart, and the first reply puts sync in effect. Afterwards a round of `resync_queries`
//! queries goes out every `resync_interval`. Only the lowest-radius sample of a round is kept.
//!
//! # Robustness
//!
//! * A reply is used only if its exchange id **and** echoed `t1` match a query still
//!   outstanding; duplicates, replies to forgotten queries and replies meant for another querier
//!   are ignored ([`ReplyOutcome::Unmatched`]). A query unanswered after `max_round_trip` is
//!   forgotten: a lost reply costs nothing but that sample.
//! * A negative round trip or a peer whose `t3` precedes its `t2` is impossible and discarded
//!   ([`ReplyOutcome::Absurd`]), as is a peer time outside what a VRPN header carries (1970 to
//!   2106) and an offset beyond `max_offset`; a round trip over `max_round_trip` is useless and
//!   discarded ([`ReplyOutcome::TooSlow`]).
//! * A sample that contradicts the estimate (the two intervals do not overlap) means a clock was
//!   stepped, or the drift changed — or a peer is lying. It is held aside
//!   ([`ReplyOutcome::Held`]); only when `step_samples` (3) contradicting samples in a row agree
//!   with each other does the history restart from them ([`ReplyOutcome::ClockStepped`]). Any
//!   sample that fits the estimate in between discards those held. A slower change of drift
//!   makes old pairs disagree; the oldest samples are then dropped until the rest agree.
//! * The query rate does not depend on what replies say: rounds follow the schedule above, and
//!   the quick round after a clock step (or a reconnection) is skipped when another started
//!   within [`QUICK_ROUND_GAP`] (a reconnection then gets a plain round). With the defaults no
//!   peer gets more than 8 + 13 queries a minute.
//! * Offsets are kept as whole microseconds plus a fraction, and fitted relative to the newest
//!   sample, so the estimate's precision never depends on the first reply of a connection.
//!
//! The bound holds for an honest peer. A lying one can move the estimate anywhere within
//! `max_offset` (it is the only witness of its own clock), but no faster than one step per
//! `step_samples` replies, and it cannot change the query rate or the estimate's precision.
//! * A peer that never answers (a C++ 07.x peer ignores these messages) never puts sync in
//!   effect, and remote timestamps pass through unchanged. While no reply has come on the
//!   connection the gap between rounds doubles from `resync_interval` up to
//!   `max_silent_interval`, so such a peer costs one 40-byte message a minute.
//! * The estimate lapses (sync no longer in effect) when no exchange has succeeded for
//!   `stale_after`.
//!
//! # Reconnection
//!
//! A new connection may reach another process, even another host, so [`ClockSync::on_connected`]
//! keeps nothing about the peer's clock: history, drift and outstanding queries are cleared
//! (also by [`ClockSync::on_disconnected`]) and a quick round starts. Exchange ids keep counting
//! and the statistics keep adding up, so a late reply from the old connection can never match a
//! new query.

use std::time::{Duration, Instant};

use crate::time::{Now, TimeVal};
pub use crate::wire::payload::clock::{Query, Reply};
#[cfg(test)]
use estimator::drift_bounds;
use estimator::Sample;
use translation::{micros, to_timeval};
pub use translation::{Translation, TRANSLATION_REUSE};

mod estimator;
mod translation;

/// Most rounds a [`ClockSync`] keeps (the upper limit of [`ClockSyncConfig::window`]).
pub const MAX_WINDOW: usize = 64;

/// Most queries outstanding at once; when full, the oldest is forgotten (counted as lost).
pub const MAX_PENDING: usize = 16;

/// Error in seconds that microsecond timestamps add to a sample: each of `t1`, `t2`, `t3` is
/// truncated by less than 1 µs, which moves the measured offset by less than 1.5 µs.
const TIMESTAMP_ERROR: f64 = 2e-6;

/// Samples closer in time than this (seconds) bound the drift too loosely to be worth a pair.
const MIN_PAIR_SPAN: f64 = 1e-3;

/// Most contradicting samples a clock step may be required to gather (the upper limit of
/// [`ClockSyncConfig::step_samples`]).
pub const MAX_STEP_SAMPLES: usize = 8;

/// Shortest gap between two quick rounds, whatever happens: a clock step (or a reconnection)
/// sooner after the last quick round gets no quick round of its own (a reconnection gets a
/// plain round), so no peer can make us query faster than `quick_queries` a minute on top of
/// the regular rounds.
pub const QUICK_ROUND_GAP: Duration = Duration::from_secs(60);

/// Tuning of a [`ClockSync`]. [`Default`] gives the values documented on each field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClockSyncConfig {
    /// Queries in the quick round that starts each connection (default 8; 1..=[`MAX_PENDING`]).
    pub quick_queries: u32,
    /// Gap between the queries of one round (default 20 ms).
    pub quick_spacing: Duration,
    /// Gap between re-sync rounds once the peer has answered (default 5 s; at least 1 ms).
    pub resync_interval: Duration,
    /// Queries in each re-sync round (default 1; 1..=[`MAX_PENDING`]). More queries per round
    /// find a low-delay exchange more often on a jittery link, at proportional cost.
    pub resync_queries: u32,
    /// Rounds whose best sample is kept, for the clock filter and the drift bound (default 32,
    /// 2..=[`MAX_WINDOW`]): 32 rounds of 5 s measure the drift over 2.6 minutes.
    pub window: usize,
    /// Replies slower than this are discarded and unanswered queries forgotten (default 1 s).
    pub max_round_trip: Duration,
    /// Sync lapses when no exchange has succeeded for this long (default 30 s).
    pub stale_after: Duration,
    /// Longest gap between rounds while the peer has never answered (default 60 s).
    pub max_silent_interval: Duration,
    /// Largest rate difference between the two clocks, in ppm (default 500, what NTP
    /// tolerates). Bounds the drift until samples bound it better.
    pub max_skew_ppm: f64,
    /// How much the rate difference may change over the window, in ppm (default 1): added to
    /// the drift error so temperature and time daemons' slewing stay inside the bound.
    pub wander_ppm: f64,
    /// Largest offset believed (default 2^32 s, all that VRPN's 32-bit header seconds can
    /// span): a reply implying a larger one is discarded as [`ReplyOutcome::Absurd`]. Where
    /// the clocks are known to be disciplined, a smaller value limits how far a lying peer can
    /// move translated times. Capped at 2^62 µs.
    pub max_offset: Duration,
    /// Contradicting samples in a row, agreeing with each other, that it takes to accept that
    /// a clock stepped (default 3; 2..=[`MAX_STEP_SAMPLES`]). Until then the estimate stands,
    /// so a peer whose replies jump back and forth cannot make it follow them.
    pub step_samples: u32,
}

impl Default for ClockSyncConfig {
    fn default() -> ClockSyncConfig {
        ClockSyncConfig {
            quick_queries: 8,
            quick_spacing: Duration::from_millis(20),
            resync_interval: Duration::from_secs(5),
            resync_queries: 1,
            window: 32,
            max_round_trip: Duration::from_secs(1),
            stale_after: Duration::from_secs(30),
            max_silent_interval: Duration::from_secs(60),
            max_skew_ppm: 500.0,
            wander_ppm: 1.0,
            max_offset: Duration::from_secs(1 << 32),
            step_samples: 3,
        }
    }
}

impl ClockSyncConfig {
    /// The configuration with every field brought into its documented range (a non-finite or
    /// negative ppm value takes the default).
    pub fn normalised(self) -> ClockSyncConfig {
        let d = ClockSyncConfig::default();
        let ppm = |v: f64, default: f64| {
            if v.is_finite() && v >= 0.0 {
                v
            } else {
                default
            }
        };
        let resync_interval = self.resync_interval.max(Duration::from_millis(1));
        ClockSyncConfig {
            quick_queries: self.quick_queries.clamp(1, MAX_PENDING as u32),
            quick_spacing: self.quick_spacing,
            resync_interval,
            resync_queries: self.resync_queries.clamp(1, MAX_PENDING as u32),
            window: self.window.clamp(2, MAX_WINDOW),
            max_round_trip: self.max_round_trip,
            stale_after: self.stale_after,
            max_silent_interval: self.max_silent_interval.max(resync_interval),
            max_skew_ppm: ppm(self.max_skew_ppm, d.max_skew_ppm),
            wander_ppm: ppm(self.wander_ppm, d.wander_ppm),
            max_offset: self
                .max_offset
                .min(Duration::from_micros(crate::time::MAX_MICROS as u64)),
            step_samples: self.step_samples.clamp(2, MAX_STEP_SAMPLES as u32),
        }
    }
}

/// The current estimate of a peer's clock, from [`ClockSync::estimate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Peer clock minus local clock, in seconds.
    pub offset: f64,
    /// The true offset is within `offset ± uncertainty` seconds (under the assumptions in the
    /// module documentation): the radius of the sample the estimate rests on, plus the drift
    /// error times the time since that sample.
    pub uncertainty: f64,
    /// How fast the offset grows, in ppm (the peer's clock rate minus ours).
    pub drift_ppm: f64,
    /// Half-width of the interval known to hold the drift, plus the allowed wander, in ppm.
    pub drift_error_ppm: f64,
    /// Round trip of the exchange the estimate rests on, in seconds.
    pub round_trip: f64,
    /// Seconds since the exchange the estimate rests on.
    pub age: f64,
    /// Rounds in the history (at most the configured window).
    pub samples: usize,
}

/// What [`ClockSync::handle_reply`] made of a reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReplyOutcome {
    /// A valid exchange, taken into the estimate (or beaten by its round's best so far).
    Used,
    /// A valid exchange that contradicts the estimate: held aside as a possible clock step.
    Held,
    /// The `step_samples`-th contradictory exchange in a row, agreeing with those held: a
    /// clock was stepped; the history restarted from them and a quick round is due (unless
    /// one ran within [`QUICK_ROUND_GAP`]).
    ClockStepped,
    /// No outstanding query has this id and `t1`: a duplicate, a reply to a forgotten query
    /// or to another querier, or any reply while disconnected.
    Unmatched,
    /// Impossible or implausible timestamps: a negative round trip, the peer's `t3` before
    /// its `t2`, a peer time a VRPN header cannot carry (before 1970, from 2106), an offset
    /// beyond `max_offset`.
    Absurd,
    /// Round trip over `max_round_trip`.
    TooSlow,
}

/// Counters since the [`ClockSync`] was made (they survive reconnections).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClockSyncStats {
    /// Queries returned by [`ClockSync::poll_query`].
    pub queries_sent: u64,
    /// Queries forgotten without a reply: none within `max_round_trip`, pushed out of a full
    /// table, or outstanding at a disconnection.
    pub queries_lost: u64,
    /// Replies that gave a valid sample ([`ReplyOutcome::Used`], `Held` or `ClockStepped`).
    pub replies_valid: u64,
    /// Replies ignored as [`ReplyOutcome::Unmatched`].
    pub replies_unmatched: u64,
    /// Replies discarded as [`ReplyOutcome::Absurd`] or [`ReplyOutcome::TooSlow`].
    pub replies_discarded: u64,
    /// Clock steps detected ([`ReplyOutcome::ClockStepped`]).
    pub clock_steps: u64,
}

/// A query sent and not yet answered.
#[derive(Clone, Copy, Debug)]
struct Pending {
    id: u32,
    sent: Now,
    round: u32,
}

/// Clock synchronisation with one peer: see the module documentation.
#[derive(Clone, Debug)]
pub struct ClockSync {
    config: ClockSyncConfig,
    /// Origin of the monotonic seconds in [`Sample::at`].
    epoch: Instant,
    connected: bool,
    next_id: u32,
    round: u32,
    /// Queries still to send in the current round (0: the next query starts a re-sync round).
    round_left: u32,
    next_send: Option<Instant>,
    /// A reply has been used on this connection.
    answered: bool,
    /// Rounds ended without any reply on this connection, for the back-off.
    silent_rounds: u32,
    pending: [Option<Pending>; MAX_PENDING],
    /// Best sample of each kept round, oldest first.
    history: [Sample; MAX_WINDOW],
    len: usize,
    /// Offset in whole microseconds that sample offsets are relative to.
    base_us: i64,
    /// Middle of the interval known to hold the drift (seconds per second).
    drift: f64,
    /// Half-width of that interval plus the wander allowance.
    drift_error: f64,
    /// Index in `history` of the sample the estimate rests on.
    anchor: usize,
    /// When the last valid sample was taken into the history.
    last_used: f64,
    /// Contradicting samples in a row that agree with each other: a clock step once there
    /// are `step_samples` of them.
    suspects: [Sample; MAX_STEP_SAMPLES],
    suspects_len: usize,
    /// When the last quick round started (it survives reconnections: see [`QUICK_ROUND_GAP`]).
    last_quick_round: Option<Instant>,
    stats: ClockSyncStats,
}

impl ClockSync {
    /// A synchroniser for a connection that is up at `now`: the quick round starts at once.
    pub fn new(config: ClockSyncConfig, now: Now) -> ClockSync {
        let config = config.normalised();
        // Ids start somewhere that depends on when we started, so that two queriers behind one
        // peer (should replies ever reach both) rarely share ids; the echoed t1 settles the rest.
        let seed = (now.wall.sec as u64)
            .wrapping_mul(1_000_003)
            .wrapping_add(now.wall.usec as u64)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let mut sync = ClockSync {
            config,
            epoch: now.mono,
            connected: false,
            next_id: (seed >> 32) as u32,
            round: 0,
            round_left: 0,
            next_send: None,
            answered: false,
            silent_rounds: 0,
            pending: [None; MAX_PENDING],
            history: [Sample::default(); MAX_WINDOW],
            len: 0,
            base_us: 0,
            drift: 0.0,
            drift_error: 0.0,
            anchor: 0,
            last_used: 0.0,
            suspects: [Sample::default(); MAX_STEP_SAMPLES],
            suspects_len: 0,
            last_quick_round: None,
            stats: ClockSyncStats::default(),
        };
        sync.on_connected(now);
        sync
    }

    /// The configuration in use (normalised).
    pub fn config(&self) -> &ClockSyncConfig {
        &self.config
    }

    /// Counters since creation.
    pub fn stats(&self) -> ClockSyncStats {
        self.stats
    }

    /// The connection (re)opened at `now`: forget the peer's clock and start a quick round.
    pub fn on_connected(&mut self, now: Now) {
        self.forget_peer();
        self.connected = true;
        self.answered = false;
        self.silent_rounds = 0;
        if self.quick_round_allowed(now.mono) {
            self.start_quick_round(now.mono);
        } else {
            self.start_plain_round(now.mono);
        }
    }

    /// The connection dropped: forget the peer's clock and send nothing until
    /// [`on_connected`](Self::on_connected).
    pub fn on_disconnected(&mut self) {
        self.forget_peer();
        self.connected = false;
        self.round_left = 0;
        self.next_send = None;
    }

    /// When [`poll_query`](Self::poll_query) next has a query to send (`None` while
    /// disconnected).
    pub fn next_deadline(&self) -> Option<Instant> {
        if self.connected {
            self.next_send
        } else {
            None
        }
    }

    /// The query to send now, if one is due. Its `query_sent` is `now.wall`, so pack it at once
    /// and stamp the message header with that time. Call again only on a later pass: at most
    /// one query is due per deadline, and a late caller gets one query, not a burst.
    pub fn poll_query(&mut self, now: Now) -> Option<Query> {
        self.expire(now);
        if !self.connected || now.mono < self.next_send? {
            return None;
        }
        if self.round_left == 0 {
            self.round = self.round.wrapping_add(1);
            self.round_left = self.config.resync_queries;
        }
        let id = self.next_id;
        self.next_id = self.next_id.wrapping_add(1);
        self.remember(Pending {
            id,
            sent: now,
            round: self.round,
        });
        self.round_left -= 1;
        let gap = if self.round_left > 0 {
            self.config.quick_spacing
        } else {
            self.gap_between_rounds()
        };
        self.next_send = Some(now.mono + gap);
        self.stats.queries_sent += 1;
        Some(Query {
            id,
            query_sent: now.wall,
        })
    }

    /// Takes a decoded reply received at `t4` (read no earlier than the reply was read from the
    /// network) and says what became of it. Never fails: whatever the peer sends, the worst is
    /// a reply ignored.
    pub fn handle_reply(&mut self, reply: &Reply, t4: Now) -> ReplyOutcome {
        let slot = self.pending.iter().position(
            |p| matches!(p, Some(p) if p.id == reply.id && p.sent.wall == reply.query_sent),
        );
        let Some(query) = slot.and_then(|i| self.pending[i].take()) else {
            self.stats.replies_unmatched += 1;
            return ReplyOutcome::Unmatched;
        };
        let sample = match self.measure(&query, reply, t4) {
            Ok(sample) => sample,
            Err(outcome) => {
                self.stats.replies_discarded += 1;
                return outcome;
            }
        };
        self.stats.replies_valid += 1;
        self.answered = true;
        self.add(sample, t4.mono)
    }

    /// The estimate at `now`, or `None` while sync is not in effect (no valid exchange yet on
    /// this connection, or none for `stale_after`, or disconnected).
    pub fn estimate(&self, now: Now) -> Option<Estimate> {
        let t = self.secs(now.mono);
        let (offset, uncertainty) = self.predict(t)?;
        let anchor = &self.history[self.anchor];
        Some(Estimate {
            offset: self.base_us as f64 * 1e-6 + offset,
            uncertainty,
            drift_ppm: self.drift * 1e6,
            drift_error_ppm: self.drift_error * 1e6,
            round_trip: anchor.round_trip,
            age: t - anchor.at,
            samples: self.len,
        })
    }

    /// Whether an estimate exists at all (a cheap test before [`in_effect`](Self::in_effect),
    /// which also checks that it is not stale and needs the time for that).
    #[inline]
    pub fn has_estimate(&self) -> bool {
        self.connected && self.len > 0
    }

    /// Whether sync is in effect at `now`: at least one valid exchange on this connection and
    /// one within `stale_after`. (It takes `now` because staleness is a matter of time.)
    pub fn in_effect(&self, now: Now) -> bool {
        self.predict(self.secs(now.mono)).is_some()
    }

    /// The local time of a peer timestamp, at `now`: `remote − offset`, with the offset taken at
    /// the moment the timestamp refers to (drift applied over its age). Returns `remote`
    /// unchanged while sync is not in effect.
    pub fn remote_to_local(&self, remote: TimeVal, now: Now) -> TimeVal {
        self.translation(now)
            .map_or(remote, |t| t.remote_to_local(remote))
    }

    /// The translation [`remote_to_local`](Self::remote_to_local) applies at `now`, worked out
    /// once so that the many messages of one `mainloop()` pass share it. `None` while sync is
    /// not in effect.
    pub fn translation(&self, now: Now) -> Option<Translation> {
        let now_us = micros(now.wall).clamp(i64::MIN as i128, i64::MAX as i128) as i64;
        Some(Translation::new(
            self.offset_micros(now)?,
            now_us,
            self.drift,
        ))
    }

    /// [`translation`](Self::translation) at `now`, and the monotonic moment until which it
    /// may be reused. The estimate is a straight line in time, and a translation applies it
    /// to each timestamp's own moment, so one worked out earlier gives the same local times
    /// (to the microsecond) until a reply changes the estimate or the estimate goes stale;
    /// reusing it spares every `mainloop()` pass the floating-point work. The moment is
    /// capped at [`TRANSLATION_REUSE`] from `now` so that a stepped wall clock is followed.
    pub fn translation_until(&self, now: Now) -> (Option<Translation>, Instant) {
        let mut until = now.mono + TRANSLATION_REUSE;
        let translation = self.translation(now);
        if translation.is_some() {
            let stale_at = Duration::try_from_secs_f64(self.last_used)
                .ok()
                .and_then(|d| self.epoch.checked_add(d + self.config.stale_after));
            if let Some(stale_at) = stale_at {
                until = until.min(stale_at);
            }
        }
        (translation, until)
    }

    /// The peer's time of a local timestamp, at `now`: the inverse of
    /// [`remote_to_local`](Self::remote_to_local). Returns `local` unchanged while sync is not in
    /// effect.
    pub fn local_to_remote(&self, local: TimeVal, now: Now) -> TimeVal {
        let Some(offset_now) = self.offset_micros(now) else {
            return local;
        };
        let local_us = micros(local);
        let age = (micros(now.wall) - local_us) as f64;
        let offset = offset_now as f64 - self.drift * age;
        to_timeval(local_us + offset.round() as i128)
    }

    /// The offset at `now` in whole microseconds.
    fn offset_micros(&self, now: Now) -> Option<i64> {
        let (offset, _) = self.predict(self.secs(now.mono))?;
        Some(self.base_us.saturating_add((offset * 1e6).round() as i64))
    }

    /// Seconds from `epoch` to `t` on the monotonic clock.
    fn secs(&self, t: Instant) -> f64 {
        t.saturating_duration_since(self.epoch).as_secs_f64()
    }

    /// Offset (relative to `base_us`) and uncertainty at monotonic seconds `t`, if in effect.
    fn predict(&self, t: f64) -> Option<(f64, f64)> {
        if !self.connected
            || self.len == 0
            || t - self.last_used > self.config.stale_after.as_secs_f64()
        {
            return None;
        }
        let a = &self.history[self.anchor];
        let dt = t - a.at;
        Some((
            a.offset + self.drift * dt,
            a.radius + self.drift_error * dt.abs(),
        ))
    }

    fn forget_peer(&mut self) {
        for p in self.pending.iter_mut() {
            if p.take().is_some() {
                self.stats.queries_lost += 1;
            }
        }
        self.len = 0;
        self.anchor = 0;
        self.drift = 0.0;
        self.drift_error = 0.0;
        self.suspects_len = 0;
    }

    /// Whether a quick round may start at `at` ([`QUICK_ROUND_GAP`] since the last one).
    pub(super) fn quick_round_allowed(&self, at: Instant) -> bool {
        self.last_quick_round.map_or(true, |last| {
            at.saturating_duration_since(last) >= QUICK_ROUND_GAP
        })
    }

    pub(super) fn start_quick_round(&mut self, at: Instant) {
        self.last_quick_round = Some(at);
        self.start_round(at, self.config.quick_queries);
    }

    fn start_plain_round(&mut self, at: Instant) {
        self.start_round(at, self.config.resync_queries);
    }

    fn start_round(&mut self, at: Instant, queries: u32) {
        self.round = self.round.wrapping_add(1);
        self.round_left = queries;
        self.next_send = Some(at);
    }

    /// Gap after a round's last query: `resync_interval`, doubled per silent round while the
    /// peer has never answered on this connection.
    fn gap_between_rounds(&mut self) -> Duration {
        if self.answered {
            return self.config.resync_interval;
        }
        let factor = 1u32 << self.silent_rounds.min(20);
        self.silent_rounds = self.silent_rounds.saturating_add(1);
        self.config
            .resync_interval
            .saturating_mul(factor)
            .min(self.config.max_silent_interval)
    }

    /// Stores an outstanding query, forgetting the oldest one if every slot is taken.
    fn remember(&mut self, query: Pending) {
        let slot = match self.pending.iter().position(Option::is_none) {
            Some(free) => free,
            None => {
                self.stats.queries_lost += 1;
                self.pending
                    .iter()
                    .enumerate()
                    .min_by_key(|(_, p)| p.map(|p| p.sent.mono))
                    .map_or(0, |(i, _)| i)
            }
        };
        self.pending[slot] = Some(query);
    }

    /// Forgets queries unanswered for longer than `max_round_trip`.
    fn expire(&mut self, now: Now) {
        let limit = self.config.max_round_trip;
        for p in self.pending.iter_mut() {
            if matches!(p, Some(q) if now.mono.saturating_duration_since(q.sent.mono) > limit) {
                *p = None;
                self.stats.queries_lost += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests;
