//! Unit tests of the clock-offset estimator.
use super::*;

const PEER_AHEAD_US: i64 = 100_000_000; // the peer's clock is 100 s ahead

fn start() -> Now {
    Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 250_000),
    }
}

fn after(now: Now, micros: u64) -> Now {
    now.plus(Duration::from_micros(micros))
}

/// The reply of a peer `PEER_AHEAD_US` ahead, for a query that took `out` µs to arrive and
/// `hold` µs to answer.
fn reply(q: &Query, out: i64, hold: i64) -> Reply {
    let received = TimeVal::from_micros(q.query_sent.as_micros() + PEER_AHEAD_US + out);
    Reply::answer(q, received, received.plus_secs(hold as f64 * 1e-6))
}

#[test]
fn one_exchange_gives_ntp_offset_and_half_the_round_trip() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    assert!(!sync.in_effect(t0));
    let q = sync.poll_query(t0).unwrap();
    assert_eq!(q.query_sent, t0.wall);
    // 1 ms out, 0.5 ms at the peer, 3 ms back: t4 − t1 = 4.5 ms, round trip 4 ms.
    let t4 = after(t0, 4_500);
    assert_eq!(
        sync.handle_reply(&reply(&q, 1_000, 500), t4),
        ReplyOutcome::Used
    );
    let e = sync.estimate(t4).unwrap();
    // ((t2 − t1) + (t3 − t4)) / 2 = (100.001 + 99.997) / 2 = 99.999 s.
    assert!((e.offset - 99.999).abs() < 1e-9, "{e:?}");
    assert!((e.round_trip - 0.004).abs() < 1e-9);
    // radius 2 ms + 2 µs rounding + 500 ppm × 4.5 ms, and 501 ppm drift error × 2.25 ms.
    let radius = 0.002 + 2e-6 + 500e-6 * 0.0045;
    let expected = radius + 501e-6 * 0.00225;
    assert!((e.uncertainty - expected).abs() < 1e-9, "{e:?}");
    // The true offset (100 s) is inside: the 2 ms asymmetry costs 1 ms of error.
    assert!((e.offset - 100.0).abs() <= e.uncertainty);
    assert_eq!(e.drift_ppm, 0.0);
    assert_eq!(e.samples, 1);
    assert!(sync.in_effect(t4));
}

#[test]
fn quick_round_then_resync_rounds_with_back_off_while_unanswered() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    assert_eq!(sync.next_deadline(), Some(t0.mono));
    let mut now = t0;
    let mut ids = [0u32; 8];
    for id in ids.iter_mut() {
        assert_eq!(sync.next_deadline(), Some(now.mono));
        *id = sync.poll_query(now).unwrap().id;
        assert!(sync.poll_query(now).is_none(), "one query per deadline");
        now = after(now, 20_000);
    }
    assert!(ids.windows(2).all(|w| w[1] == w[0].wrapping_add(1)));
    // Nobody answers: 5, 10, 20, 40, then 60 s capped.
    let mut last = now.mono - Duration::from_millis(20);
    for gap in [5, 10, 20, 40, 60, 60, 60] {
        let due = sync.next_deadline().unwrap();
        assert_eq!(due - last, Duration::from_secs(gap));
        let at = Now {
            mono: due,
            wall: t0.wall,
        };
        assert!(sync.poll_query(at).is_some());
        last = due;
    }
    assert_eq!(sync.stats().queries_sent, 15);
    assert!(sync.stats().queries_lost >= 8);
}

#[test]
fn an_answered_peer_is_re_synced_every_interval() {
    let config = ClockSyncConfig {
        quick_queries: 2,
        resync_queries: 3,
        ..ClockSyncConfig::default()
    };
    let t0 = start();
    let mut sync = ClockSync::new(config, t0);
    let q = sync.poll_query(t0).unwrap();
    let t = after(t0, 20_000);
    assert!(sync.poll_query(t).is_some());
    assert_eq!(sync.next_deadline(), Some(t.mono + Duration::from_secs(5)));
    sync.handle_reply(&reply(&q, 300, 10), after(t0, 25_000));
    // A re-sync round of 3 queries, 20 ms apart, then the plain interval.
    let mut now = after(t, 5_000_000);
    for _ in 0..3 {
        assert!(sync.poll_query(now).is_some());
        now = after(now, 20_000);
    }
    let last = now.mono - Duration::from_millis(20);
    assert_eq!(sync.next_deadline(), Some(last + Duration::from_secs(5)));
}

#[test]
fn a_late_caller_gets_one_query_not_a_burst() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    let late = after(t0, 3_000_000);
    assert!(sync.poll_query(late).is_some());
    assert!(sync.poll_query(late).is_none());
    assert_eq!(
        sync.next_deadline(),
        Some(late.mono + Duration::from_millis(20))
    );
}

#[test]
fn duplicate_foreign_and_forgotten_replies_are_unmatched() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    let q = sync.poll_query(t0).unwrap();
    let r = reply(&q, 200, 10);
    let t4 = after(t0, 1_000);
    // Same id, different t1: another querier's exchange.
    let mut foreign = r;
    foreign.query_sent = foreign.query_sent.plus_secs(1e-6);
    assert_eq!(sync.handle_reply(&foreign, t4), ReplyOutcome::Unmatched);
    let mut unknown = r;
    unknown.id = q.id.wrapping_add(1000);
    assert_eq!(sync.handle_reply(&unknown, t4), ReplyOutcome::Unmatched);
    assert_eq!(sync.handle_reply(&r, t4), ReplyOutcome::Used);
    assert_eq!(sync.handle_reply(&r, t4), ReplyOutcome::Unmatched);
    // A query unanswered for over max_round_trip is forgotten; its late reply is ignored.
    let now = after(t0, 20_000);
    let q2 = sync.poll_query(now).unwrap();
    let much_later = after(now, 1_500_000);
    assert_eq!(sync.stats().queries_lost, 0);
    sync.poll_query(much_later); // forgets what expired before sending the next query
    assert_eq!(sync.stats().queries_lost, 1);
    assert_eq!(
        sync.handle_reply(&reply(&q2, 200, 10), much_later),
        ReplyOutcome::Unmatched
    );
    let s = sync.stats();
    assert_eq!((s.replies_valid, s.replies_unmatched), (1, 4));
}

#[test]
fn impossible_and_slow_replies_are_discarded() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    // The peer claims to have sent its reply before receiving the query.
    let q = sync.poll_query(t0).unwrap();
    let mut r = reply(&q, 200, 10);
    r.reply_sent = r.query_received.plus_secs(-1e-6);
    assert_eq!(
        sync.handle_reply(&r, after(t0, 1_000)),
        ReplyOutcome::Absurd
    );
    // The peer claims to have held the query longer than the whole round trip took.
    let now = after(t0, 20_000);
    let q = sync.poll_query(now).unwrap();
    assert_eq!(
        sync.handle_reply(&reply(&q, 200, 5_000), after(now, 1_000)),
        ReplyOutcome::Absurd
    );
    // A round trip over max_round_trip (answered before the query expired).
    let now = after(now, 20_000);
    let q = sync.poll_query(now).unwrap();
    assert_eq!(
        sync.handle_reply(&reply(&q, 200, 10), after(now, 1_000_100)),
        ReplyOutcome::TooSlow
    );
    assert_eq!(sync.stats().replies_discarded, 3);
    assert!(!sync.in_effect(after(now, 1_000_100)));
    // Within the 2 µs rounding allowance a slightly negative round trip is still valid.
    let now = after(now, 20_000);
    let q = sync.poll_query(now).unwrap();
    assert_eq!(
        sync.handle_reply(&reply(&q, 200, 1_001), after(now, 1_000)),
        ReplyOutcome::Used
    );
}

#[test]
fn disconnection_forgets_the_peer_and_reconnection_starts_over() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    let q = sync.poll_query(t0).unwrap();
    let t4 = after(t0, 1_000);
    sync.handle_reply(&reply(&q, 200, 10), t4);
    let q2 = sync.poll_query(after(t0, 20_000)).unwrap();
    assert!(sync.in_effect(t4));

    sync.on_disconnected();
    let t = after(t0, 30_000);
    assert!(!sync.in_effect(t));
    assert_eq!(sync.estimate(t), None);
    assert_eq!(sync.next_deadline(), None);
    assert!(sync.poll_query(after(t0, 10_000_000)).is_none());
    let stamp = TimeVal::new(1_700_000_100, 0);
    assert_eq!(sync.remote_to_local(stamp, t), stamp);
    // A reply from the old connection matches nothing.
    assert_eq!(
        sync.handle_reply(&reply(&q2, 200, 10), t),
        ReplyOutcome::Unmatched
    );

    // Back 2 s after the first quick round: a plain round (one query) at once, no second
    // quick round within a minute.
    let back = after(t0, 2_000_000);
    sync.on_connected(back);
    assert_eq!(sync.next_deadline(), Some(back.mono));
    let q3 = sync.poll_query(back).unwrap();
    assert_eq!(q3.id, q2.id.wrapping_add(1), "ids keep counting");
    assert_eq!(
        sync.next_deadline(),
        Some(back.mono + Duration::from_secs(5))
    );
    assert!(!sync.in_effect(back));
    sync.handle_reply(&reply(&q3, 200, 10), after(back, 1_000));
    assert_eq!(sync.estimate(after(back, 1_000)).unwrap().samples, 1);

    // A minute after the last quick round a reconnection gets a quick round again.
    sync.on_disconnected();
    let later = after(t0, 60_000_000);
    sync.on_connected(later);
    assert!(sync.poll_query(later).is_some());
    assert_eq!(
        sync.next_deadline(),
        Some(later.mono + Duration::from_millis(20))
    );
}

#[test]
fn sync_lapses_when_no_exchange_succeeds_for_stale_after() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    let q = sync.poll_query(t0).unwrap();
    sync.handle_reply(&reply(&q, 200, 10), after(t0, 1_000));
    assert!(sync.in_effect(after(t0, 30_000_000)));
    assert!(!sync.in_effect(after(t0, 30_001_000)));
}

#[test]
fn translation_applies_the_offset_both_ways() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    let q = sync.poll_query(t0).unwrap();
    // Symmetric 500 µs each way: the measured offset is exactly 100 s.
    let t4 = after(t0, 1_010);
    sync.handle_reply(&reply(&q, 500, 10), t4);
    let e = sync.estimate(t4).unwrap();
    assert!((e.offset - 100.0).abs() < 1e-9, "{e:?}");
    let remote = TimeVal::new(1_700_000_100, 300_000);
    let local = sync.remote_to_local(remote, t4);
    assert_eq!(local, TimeVal::new(1_700_000_000, 300_000));
    assert_eq!(sync.local_to_remote(local, t4), remote);
}

#[test]
fn translation_follows_the_drift_over_the_age_of_a_timestamp() {
    let config = ClockSyncConfig {
        quick_queries: 1,
        resync_interval: Duration::from_secs(10),
        ..ClockSyncConfig::default()
    };
    let t0 = start();
    let mut sync = ClockSync::new(config, t0);
    // Two instantaneous exchanges 10 s apart; the peer gains 1 ms meanwhile (100 ppm).
    let q = sync.poll_query(t0).unwrap();
    sync.handle_reply(&reply(&q, 0, 0), t0);
    let t1 = after(t0, 10_000_000);
    let q = sync.poll_query(t1).unwrap();
    let mut r = reply(&q, 0, 0);
    r.query_received = r.query_received.plus_secs(1e-3);
    r.reply_sent = r.query_received;
    assert_eq!(sync.handle_reply(&r, t1), ReplyOutcome::Used);
    let e = sync.estimate(t1).unwrap();
    // 1 ms ± 4 µs over 10 s: 99.6..100.4 ppm.
    assert!((e.drift_ppm - 100.0).abs() < 1e-6, "{e:?}");
    assert!((e.drift_error_ppm - 1.4).abs() < 1e-6, "{e:?}");
    assert!((e.offset - 100.001).abs() < 1e-9);
    // A peer timestamp of 5 s ago: the offset then was 100.0005 s, not 100.001 s.
    let local_then = t1.wall.plus_secs(-5.0);
    let remote_then = local_then.plus_secs(100.0005);
    assert_eq!(sync.remote_to_local(remote_then, t1), local_then);
    assert_eq!(sync.local_to_remote(local_then, t1), remote_then);
    // And one 5 s ahead (a peer timestamp in our future).
    let local_soon = t1.wall.plus_secs(5.0);
    let remote_soon = local_soon.plus_secs(100.0015);
    assert_eq!(sync.remote_to_local(remote_soon, t1), local_soon);

    // A translation worked out earlier and reused gives the fresh one's local times,
    // until its reuse limit.
    let (early, until) = sync.translation_until(t1);
    let early = early.expect("in effect");
    assert_eq!(until, t1.mono + TRANSLATION_REUSE);
    let t2 = after(t1, 200_000);
    for age_ms in [0i64, 3, 150, 4_000] {
        let local = t2.wall.plus_secs(-(age_ms as f64) * 1e-3);
        let remote = sync.local_to_remote(local, t2);
        let fresh = sync.remote_to_local(remote, t2);
        let reused = early.remote_to_local(remote);
        assert!(
            (fresh.as_micros() - reused.as_micros()).abs() <= 1,
            "{age_ms} ms: {fresh} vs {reused}"
        );
    }
}

#[test]
fn a_reused_translation_ends_when_the_estimate_goes_stale() {
    let t0 = start();
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    let q = sync.poll_query(t0).unwrap();
    sync.handle_reply(&reply(&q, 200, 10), after(t0, 1_000));
    let near_end = after(t0, 29_900_000);
    let (t, until) = sync.translation_until(near_end);
    assert!(t.is_some());
    // Stale 30 s after the sample (taken half-way through the 1 ms exchange).
    assert_eq!(until, after(t0, 30_000_500).mono);
    let (t, _) = sync.translation_until(after(t0, 30_001_000));
    assert!(t.is_none());
}

#[test]
fn a_full_table_of_outstanding_queries_forgets_the_oldest() {
    let config = ClockSyncConfig {
        quick_queries: 100,
        max_round_trip: Duration::from_secs(10),
        ..ClockSyncConfig::default()
    };
    let t0 = start();
    let mut sync = ClockSync::new(config, t0);
    assert_eq!(sync.config().quick_queries, MAX_PENDING as u32);
    let mut now = t0;
    let first = sync.poll_query(now).unwrap();
    for _ in 1..MAX_PENDING {
        now = after(now, 20_000);
        sync.poll_query(now).unwrap();
    }
    assert_eq!(sync.stats().queries_lost, 0);
    // The first query of the next round needs a slot: the oldest query gives up its own.
    now = after(now, 5_000_000);
    let last = sync.poll_query(now).unwrap();
    assert_eq!(sync.stats().queries_lost, 1);
    let t4 = after(now, 1_000);
    assert_eq!(
        sync.handle_reply(&reply(&first, 200, 10), t4),
        ReplyOutcome::Unmatched
    );
    assert_eq!(
        sync.handle_reply(&reply(&last, 200, 10), t4),
        ReplyOutcome::Used
    );
}

#[test]
fn configuration_is_brought_into_range() {
    let c = ClockSyncConfig {
        quick_queries: 0,
        resync_interval: Duration::ZERO,
        resync_queries: 1000,
        window: 1000,
        max_silent_interval: Duration::ZERO,
        max_skew_ppm: f64::NAN,
        wander_ppm: -3.0,
        ..ClockSyncConfig::default()
    }
    .normalised();
    assert_eq!(c.quick_queries, 1);
    assert_eq!(c.resync_interval, Duration::from_millis(1));
    assert_eq!(c.resync_queries, MAX_PENDING as u32);
    assert_eq!(c.window, MAX_WINDOW);
    assert_eq!(c.max_silent_interval, c.resync_interval);
    assert_eq!(c.max_skew_ppm, 500.0);
    assert_eq!(c.wander_ppm, 1.0);
    assert_eq!(
        ClockSyncConfig::default().normalised(),
        ClockSyncConfig::default()
    );
}

#[test]
fn drift_is_bounded_by_every_pair_of_samples() {
    let a = Sample {
        at: 0.0,
        offset: 0.0,
        radius: 1e-3,
        ..Sample::default()
    };
    let b = Sample {
        at: 10.0,
        offset: 1e-3,
        radius: 1e-3,
        ..Sample::default()
    };
    // (1 ms ± 2 ms) over 10 s: −100..+300 ppm, whichever sample comes first.
    let (low, high) = drift_bounds(&a, &b).unwrap();
    assert!((low + 100e-6).abs() < 1e-12 && (high - 300e-6).abs() < 1e-12);
    assert_eq!(drift_bounds(&b, &a), Some((low, high)));
    let close = Sample { at: 0.0005, ..b };
    assert_eq!(drift_bounds(&a, &close), None);
}

/// The integer shortcut for fresh timestamps gives exactly what the floating-point rule gives,
/// on both sides of its age limit, for drifts from none to far beyond any real clock's.
#[test]
fn translating_fresh_timestamps_skips_only_drift_that_rounds_to_nothing() {
    let reference = |t: &Translation, remote: TimeVal| {
        let remote_us = remote.sec * 1_000_000 + remote.usec;
        let age = (t.now_us - (remote_us - t.offset_us)) as f64;
        let back = (t.drift * age).round() as i64;
        TimeVal::from_micros(remote_us - t.offset_us + back)
    };
    let now_us = 1_700_000_000_000_000i64;
    let mut checked = 0;
    for drift in [0.0, 1e-9, 3.7e-7, -2.5e-6, 1e-5, -1e-4, 5e-4, 0.01, -0.3] {
        for offset_us in [0i64, 123_456_789, -987_654_321] {
            let t = Translation::new(offset_us, now_us, drift);
            let limit = t.drift_free_age_us.min(1 << 40);
            for age in [
                0,
                1,
                -1,
                999,
                limit - 1,
                limit,
                limit + 1,
                -limit,
                -limit - 1,
                2 * limit + 3,
            ] {
                // A timestamp whose translation lies `age` µs before `now_us`.
                let remote = TimeVal::from_micros(now_us - age + offset_us);
                assert_eq!(
                    t.remote_to_local(remote),
                    reference(&t, remote),
                    "drift {drift}, offset {offset_us} µs, age {age} µs"
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 9 * 3 * 10);
}

/// A peer's clock pass translates a repeated timestamp (the sensors of one frame) from its
/// last result, the same as translating it afresh; a new timestamp is translated anew, and
/// without a translation times pass unchanged.
#[test]
fn a_clock_pass_reuses_the_last_translation_only_for_the_same_timestamp() {
    use crate::proto::endpoint::ClockPass;
    let t = Translation::new(-2_500_000, 1_700_000_000_000_000, 3e-5);
    let mut pass = ClockPass {
        translation: Some(t),
        until: Instant::now(),
        last: None,
    };
    let frame = TimeVal::new(1_700_000_000, 900_000);
    let next = TimeVal::new(1_700_000_000, 900_001);
    let old = TimeVal::new(1_699_999_000, 0); // old enough for the drift term to count
    for remote in [frame, frame, next, frame, old, old, frame] {
        assert_eq!(
            pass.translate(remote),
            t.remote_to_local(remote),
            "{remote}"
        );
        assert_eq!(pass.last, Some((remote, t.remote_to_local(remote))));
    }
    assert_ne!(
        t.remote_to_local(old).as_micros() - old.as_micros(),
        2_500_000
    );
    let mut off = ClockPass {
        translation: None,
        until: Instant::now(),
        last: None,
    };
    assert_eq!(off.translate(frame), frame);
}

#[test]
fn offsets_beyond_max_offset_and_peer_times_a_header_cannot_carry_are_absurd() {
    let config = ClockSyncConfig {
        max_offset: Duration::from_secs(60),
        ..ClockSyncConfig::default()
    };
    let t0 = start();
    let mut sync = ClockSync::new(config, t0);
    // The peer is 100 s ahead: more than the 60 s this deployment believes.
    let q = sync.poll_query(t0).unwrap();
    assert_eq!(
        sync.handle_reply(&reply(&q, 200, 10), after(t0, 1_000)),
        ReplyOutcome::Absurd
    );
    // With the default bound it is fine; a peer reading 2106 or 1969 is not.
    let mut sync = ClockSync::new(ClockSyncConfig::default(), t0);
    let mut now = t0;
    for (peer_us, outcome) in [
        ((1i64 << 32) * 1_000_000, ReplyOutcome::Absurd),
        (-1, ReplyOutcome::Absurd),
        (0, ReplyOutcome::Used),
    ] {
        let q = sync.poll_query(now).unwrap();
        let at = TimeVal::from_micros(peer_us);
        let r = Reply::answer(&q, at, at);
        assert_eq!(sync.handle_reply(&r, after(now, 100)), outcome, "{peer_us}");
        now = after(now, 20_000);
    }
    assert_eq!(
        ClockSyncConfig {
            max_offset: Duration::MAX,
            step_samples: 100,
            ..ClockSyncConfig::default()
        }
        .normalised(),
        ClockSyncConfig {
            max_offset: Duration::from_micros(crate::time::MAX_MICROS as u64),
            step_samples: MAX_STEP_SAMPLES as u32,
            ..ClockSyncConfig::default()
        }
    );
}

/// A step needs `step_samples` contradicting replies in a row that agree with each other; one
/// that fits the estimate in between discards those held.
#[test]
fn a_step_needs_agreeing_contradictions_in_a_row() {
    let config = ClockSyncConfig {
        quick_queries: 1,
        ..ClockSyncConfig::default()
    };
    let t0 = start();
    let mut sync = ClockSync::new(config, t0);
    let mut now = t0;
    let mut exchange = |sync: &mut ClockSync, shift_us: i64| {
        now = after(now, 5_000_000);
        let q = sync.poll_query(now).unwrap();
        let r = reply(&q, 200, 10);
        let moved = |t: TimeVal| TimeVal::from_micros(t.as_micros() + shift_us);
        let r = Reply::answer(&q, moved(r.query_received), moved(r.reply_sent));
        sync.handle_reply(&r, after(now, 400))
    };
    assert_eq!(exchange(&mut sync, 0), ReplyOutcome::Used);
    assert_eq!(exchange(&mut sync, 2_000_000), ReplyOutcome::Held);
    assert_eq!(
        exchange(&mut sync, 0),
        ReplyOutcome::Used,
        "fits: the held one goes"
    );
    assert_eq!(exchange(&mut sync, 2_000_000), ReplyOutcome::Held);
    assert_eq!(
        exchange(&mut sync, -2_000_000),
        ReplyOutcome::Held,
        "disagrees: restarts"
    );
    assert_eq!(
        exchange(&mut sync, 2_000_000),
        ReplyOutcome::Held,
        "restarts again"
    );
    assert_eq!(exchange(&mut sync, 2_000_000), ReplyOutcome::Held);
    assert_eq!(exchange(&mut sync, 2_000_000), ReplyOutcome::ClockStepped);
    let e = sync.estimate(now).unwrap();
    assert!((e.offset - 102.0).abs() < 1e-5, "{e:?}");
    assert_eq!(e.samples, 3);
    assert_eq!(sync.stats().clock_steps, 1);
}
