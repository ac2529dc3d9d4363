//! Clock synchronisation against malicious servers, on virtual time: replies claiming absurd
//! times, offsets that jump back and forth, a poisoned first sample followed by honest
//! replies. Whatever the replies say, the estimate must not follow a peer faster than the
//! step rule allows, must keep its precision, must never state an uncertainty it does not
//! have while the peer is honest, and the query rate must stay on its schedule.
//!
//! `cargo test --release --test clock_sync_hostile -- --nocapture` prints the figures.

use std::time::{Duration, Instant};

use vrpn::proto::clock::{ClockSync, ClockSyncConfig, Query, Reply, ReplyOutcome};
use vrpn::wire::payload::clock::MAX_TIME_MICROS;
use vrpn::{Now, TimeVal};

const MS: u64 = 1_000_000;
const SEC: u64 = 1_000 * MS;
const MINUTE: u64 = 60 * SEC;
/// The querier's wall clock at true time 0.
const LOCAL_START_US: i64 = 1_700_000_000_000_000;
/// The honest peer's clock: 7.25 s ahead of ours.
const PEER_AHEAD_US: i64 = 7_250_000;
/// Delays of the virtual link (asymmetric: the estimate is off by half the difference,
/// 100 µs, which its bound must cover) and the peer's time to answer.
const OUT_NS: u64 = 100_000;
const BACK_NS: u64 = 300_000;
const HOLD_NS: u64 = 10_000;

/// What a responder makes of the `n`-th query (0-based): the honest reply is given; it may
/// return it, change it, or return `None` to stay silent.
type Responder = Box<dyn FnMut(u64, Reply) -> Option<Reply>>;

struct Rig {
    t: u64,
    base: Instant,
    sync: ClockSync,
    /// Replies on their way back: (arrival, reply).
    replies: Vec<(u64, Reply)>,
    /// Queries on their way out: (arrival, query).
    queries: Vec<(u64, Query)>,
    responder: Responder,
    answered: u64,
    /// True times of every query sent.
    sent: Vec<u64>,
    outcomes: Vec<ReplyOutcome>,
}

impl Rig {
    fn new(config: ClockSyncConfig, responder: Responder) -> Rig {
        let base = Instant::now();
        let now = Now {
            mono: base,
            wall: TimeVal::from_micros(LOCAL_START_US),
        };
        Rig {
            t: 0,
            base,
            sync: ClockSync::new(config, now),
            replies: Vec::new(),
            queries: Vec::new(),
            responder,
            answered: 0,
            sent: Vec::new(),
            outcomes: Vec::new(),
        }
    }

    fn now(&self) -> Now {
        Now {
            mono: self.base + Duration::from_nanos(self.t),
            wall: TimeVal::from_micros(LOCAL_START_US + (self.t / 1000) as i64),
        }
    }

    fn peer_wall(t: u64) -> TimeVal {
        TimeVal::from_micros(LOCAL_START_US + PEER_AHEAD_US + (t / 1000) as i64)
    }

    /// Runs to true time `end`, calling `check` every `every` ns.
    fn run(&mut self, end: u64, every: u64, mut check: impl FnMut(&mut Rig)) {
        let mut next_check = (self.t / every + 1) * every;
        while self.t < end {
            let deadline = self
                .sync
                .next_deadline()
                .map_or(u64::MAX, |d| d.duration_since(self.base).as_nanos() as u64);
            let arrival = self
                .queries
                .iter()
                .map(|(t, _)| *t)
                .chain(self.replies.iter().map(|(t, _)| *t))
                .min()
                .unwrap_or(u64::MAX);
            self.t = deadline.min(arrival).min(next_check).min(end).max(self.t);
            self.deliver();
            while let Some(q) = self.sync.poll_query(self.now()) {
                self.sent.push(self.t);
                self.queries.push((self.t + OUT_NS, q));
            }
            if self.t == next_check {
                check(self);
                next_check += every;
            }
        }
    }

    fn deliver(&mut self) {
        let t = self.t;
        let mut i = 0;
        while i < self.queries.len() {
            if self.queries[i].0 <= t {
                let (at, q) = self.queries.swap_remove(i);
                let honest = Reply::answer(&q, Rig::peer_wall(at), Rig::peer_wall(at + HOLD_NS));
                let n = self.answered;
                self.answered += 1;
                if let Some(r) = (self.responder)(n, honest) {
                    self.replies.push((at + HOLD_NS + BACK_NS, r));
                }
            } else {
                i += 1;
            }
        }
        let mut i = 0;
        while i < self.replies.len() {
            if self.replies[i].0 <= t {
                let (_, r) = self.replies.swap_remove(i);
                // Through the wire codec, as the session would decode it.
                let mut buf = [0u8; Reply::LEN];
                r.encode(&mut buf);
                if let Ok(r) = Reply::decode(&buf) {
                    let outcome = self.sync.handle_reply(&r, self.now());
                    self.outcomes.push(outcome);
                }
            } else {
                i += 1;
            }
        }
    }

    /// Most queries sent in any window of `span` ns.
    fn most_queries_in(&self, span: u64) -> usize {
        (0..self.sent.len())
            .map(|i| {
                self.sent[i..]
                    .iter()
                    .take_while(|&&t| t < self.sent[i] + span)
                    .count()
            })
            .max()
            .unwrap_or(0)
    }
}

/// A reply whose peer times are moved by `us` microseconds.
fn shifted(mut r: Reply, us: i64) -> Reply {
    r.query_received = TimeVal::from_micros(r.query_received.as_micros() + us);
    r.reply_sent = TimeVal::from_micros(r.reply_sent.as_micros() + us);
    r
}

/// A reply claiming the peer's clock reads `us` microseconds since 1970 (both times).
fn claiming(mut r: Reply, us: i64) -> Reply {
    r.query_received = TimeVal::from_micros(us);
    r.reply_sent = TimeVal::from_micros(us + 10);
    r
}

/// With the default schedule (a quick round of 8 at most once a minute, one query every 5 s)
/// no window of a minute holds more than this many queries, whatever the replies.
const MOST_PER_MINUTE: usize = 8 + 13;

#[test]
fn replies_claiming_absurd_times_are_discarded() {
    for claim in [
        MAX_TIME_MICROS,
        -MAX_TIME_MICROS,
        1 << 60,
        -1,
        (1i64 << 32) * 1_000_000,
    ] {
        let mut rig = Rig::new(
            ClockSyncConfig::default(),
            Box::new(move |_, r| Some(claiming(r, claim))),
        );
        let mut translated_off = 0u64;
        rig.run(5 * SEC, 10 * MS, |rig| {
            let now = rig.now();
            assert_eq!(rig.sync.estimate(now), None, "claim {claim}");
            let stamp = Rig::peer_wall(rig.t);
            if rig.sync.remote_to_local(stamp, now) != stamp {
                translated_off += 1;
            }
        });
        assert!(
            rig.outcomes.iter().all(|o| *o == ReplyOutcome::Absurd),
            "claim {claim}: {:?}",
            rig.outcomes
        );
        assert_eq!(translated_off, 0, "timestamps pass unchanged");
        assert!(rig.sent.len() <= 9, "{} queries in 5 s", rig.sent.len());
    }
}

#[test]
fn an_offset_jumping_back_and_forth_is_not_followed() {
    // The replies claim the peer's clock 1,000 s ahead of, then behind, the truth, switching
    // every reply or every two replies.
    for period in [1u64, 2] {
        let mut rig = Rig::new(
            ClockSyncConfig::default(),
            Box::new(move |n, r| {
                let ahead = (n / period) % 2 == 0;
                Some(shifted(
                    r,
                    if ahead { 1_000_000_000 } else { -1_000_000_000 },
                ))
            }),
        );
        let mut flips = 0;
        let mut last: Option<f64> = None;
        rig.run(5 * SEC, MS, |rig| {
            if let Some(e) = rig.sync.estimate(rig.now()) {
                if last.is_some_and(|l| (l - e.offset).abs() > 1.0) {
                    flips += 1;
                }
                last = Some(e.offset);
            }
        });
        let stats = rig.sync.stats();
        eprintln!(
            "±1000 s switching every {period} replies, 5 s: {flips} flips of the estimate, {} \
             clock steps, {} queries",
            stats.clock_steps,
            rig.sent.len()
        );
        assert_eq!(flips, 0, "period {period}");
        assert_eq!(stats.clock_steps, 0, "period {period}");
        assert!(rig.sent.len() <= 9, "{} queries in 5 s", rig.sent.len());
    }
}

#[test]
fn a_peer_stepping_as_often_as_it_can_gets_no_more_queries() {
    // Runs of three replies 1,000 s apart in turn: every run is a confirmed step, the most a
    // liar can get. Ten minutes of it.
    let mut rig = Rig::new(
        ClockSyncConfig::default(),
        Box::new(|n, r| {
            Some(shifted(
                r,
                if (n / 3) % 2 == 0 {
                    1_000_000_000
                } else {
                    -1_000_000_000
                },
            ))
        }),
    );
    let mut flips = 0;
    let mut last: Option<f64> = None;
    rig.run(10 * MINUTE, 10 * MS, |rig| {
        if let Some(e) = rig.sync.estimate(rig.now()) {
            if last.is_some_and(|l| (l - e.offset).abs() > 1.0) {
                flips += 1;
            }
            last = Some(e.offset);
        }
    });
    let stats = rig.sync.stats();
    let most = rig.most_queries_in(MINUTE);
    eprintln!(
        "runs of 3 replies ±1000 s, 10 min: {} queries ({most} in the busiest minute), {} \
         clock steps, {flips} flips",
        rig.sent.len(),
        stats.clock_steps
    );
    assert!(most <= MOST_PER_MINUTE, "{most} queries in a minute");
    // Each step needs three replies in a row.
    assert!(stats.clock_steps * 3 <= stats.replies_valid, "{stats:?}");
    assert!(flips as u64 <= stats.clock_steps);
}

#[test]
fn whatever_the_replies_the_query_rate_stays_on_schedule() {
    // Pseudo-random liars: each reply shifted by one of a few offsets, or absurd, or missing,
    // or duplicated-looking (same as the last), chosen by a small PRNG per seed.
    for seed in 1..=20u64 {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let mut rig = Rig::new(
            ClockSyncConfig::default(),
            Box::new(move |_, r| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                match state % 7 {
                    0 => None,
                    1 => Some(claiming(r, MAX_TIME_MICROS)),
                    2 => Some(shifted(r, 3_000_000)),
                    3 => Some(shifted(r, -3_000_000)),
                    4 => Some(shifted(r, 1)),
                    _ => Some(r),
                }
            }),
        );
        rig.run(10 * MINUTE, SEC, |_| {});
        let most = rig.most_queries_in(MINUTE);
        assert!(
            most <= MOST_PER_MINUTE,
            "seed {seed}: {most} queries in a minute"
        );
        assert!(rig.sent.len() <= 10 * MOST_PER_MINUTE, "seed {seed}");
    }
}

/// The third case: replies at the edge of what the wire carries, then only honest
/// ones; and a first reply claiming the peer's clock reads 1970 (an offset of −54 years, which
/// a header can carry), then honest ones. Either way, once the honest replies have taken over,
/// the estimate is as precise as if the first replies had never come, and never states an
/// uncertainty it does not have.
#[test]
fn precision_does_not_depend_on_the_first_replies() {
    let cases: [(&str, i64, u64); 3] = [
        ("2^62 µs", MAX_TIME_MICROS - 987_654_321, 3),
        ("-2^62 µs", -MAX_TIME_MICROS + 123_456_789, 3),
        ("1970", 0, 1),
    ];
    for (name, claim, bad) in cases {
        let mut rig = Rig::new(
            ClockSyncConfig::default(),
            Box::new(move |n, r| Some(if n < bad { claiming(r, claim) } else { r })),
        );
        let truth = PEER_AHEAD_US as f64 * 1e-6;
        let mut worst = 0.0f64;
        let mut worst_ratio = 0.0f64;
        let mut checked = 0;
        rig.run(60 * SEC, MS, |rig| {
            let Some(e) = rig.sync.estimate(rig.now()) else {
                return;
            };
            if (e.offset - truth).abs() > 1.0 {
                return; // the poisoned estimate, before the step to the honest clock
            }
            let error = (e.offset - truth).abs();
            worst = worst.max(error);
            worst_ratio = worst_ratio.max(error / e.uncertainty);
            checked += 1;
            // A fresh peer timestamp translates to our clock within the bound (and the
            // microsecond rounding of the translation).
            let stamp = Rig::peer_wall(rig.t);
            let local = rig.sync.remote_to_local(stamp, rig.now());
            let local_error = local.seconds_since(rig.now().wall).abs();
            assert!(
                local_error <= e.uncertainty + 1e-6,
                "{name}: translated {:.1} µs off, stated {:.1} µs",
                local_error * 1e6,
                e.uncertainty * 1e6
            );
        });
        eprintln!(
            "{name} first, then honest: {checked} checks, worst error {:.2} µs, worst \
             error/uncertainty {worst_ratio:.2}",
            worst * 1e6
        );
        assert!(checked > 55_000, "{name}: {checked}");
        assert!(worst_ratio <= 1.0, "{name}");
        // The link's asymmetry costs 100 µs; anything more is lost precision.
        assert!(worst < 102e-6, "{name}: {worst}");
    }
}
