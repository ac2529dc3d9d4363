//! The estimator behind [`ClockSync`]: exchanges become samples, samples a history, the history
//! a drift interval and an anchor; contradicting samples are held until enough of them agree
//! that a clock stepped.
//!
//! Offsets are kept exactly: a sample's offset is whole microseconds (`i64`) plus a small
//! fraction, and the floating-point offsets the fit works with are taken relative to a base
//! that follows the newest sample. Their precision therefore never depends on where the first
//! sample of a connection put the base (a first reply claiming an absurd offset cannot leave
//! later, honest ones on a coarse grid).

use std::time::Instant;

use super::translation::micros;
use super::{ClockSync, Pending, ReplyOutcome, MIN_PAIR_SPAN, TIMESTAMP_ERROR};
use crate::time::Now;
use crate::wire::payload::clock::Reply;

/// Latest time (µs since 1970) a peer's clock may read: what a VRPN message header carries
/// (unsigned 32-bit seconds). A peer claiming a time outside cannot stamp its own messages.
const LATEST_PEER_TIME_US: i128 = (u32::MAX as i128 + 1) * 1_000_000;

/// One exchange, reduced to what the estimator needs. Times are seconds on the local monotonic
/// clock since [`ClockSync`] was made.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Sample {
    /// Middle of the exchange (`t1` + half the local interval).
    pub(super) at: f64,
    /// Measured offset, whole microseconds (rounded down) ...
    pub(super) offset_us: i64,
    /// ... plus this many seconds (less than a second either way: the fraction of the
    /// microsecond and half the local interval).
    pub(super) offset_frac: f64,
    /// The measured offset relative to `ClockSync::base_us`, in seconds (kept up to date for
    /// the samples in the history).
    pub(super) offset: f64,
    /// The true offset at `at` is within `offset ± radius`.
    pub(super) radius: f64,
    /// Round trip.
    pub(super) round_trip: f64,
    /// Round the query belonged to.
    pub(super) round: u32,
}

impl Sample {
    /// The offset relative to `base_us` microseconds, in seconds.
    fn relative_to(&self, base_us: i64) -> f64 {
        (self.offset_us.saturating_sub(base_us)) as f64 * 1e-6 + self.offset_frac
    }

    /// `self`'s offset minus `other`'s, in seconds, without going through a common base.
    fn minus(&self, other: &Sample) -> f64 {
        self.relative_to(other.offset_us) - other.offset_frac
    }
}

impl ClockSync {
    /// Turns a matched reply into a sample, or says why it is unusable.
    pub(super) fn measure(
        &mut self,
        query: &Pending,
        reply: &Reply,
        t4: Now,
    ) -> Result<Sample, ReplyOutcome> {
        let local = t4
            .mono
            .checked_duration_since(query.sent.mono)
            .ok_or(ReplyOutcome::Absurd)?
            .as_secs_f64();
        let t1 = micros(query.sent.wall);
        let t2 = micros(reply.query_received);
        let t3 = micros(reply.reply_sent);
        if t3 < t2 || t2 < 0 || t3 >= LATEST_PEER_TIME_US {
            return Err(ReplyOutcome::Absurd);
        }
        let round_trip = local - (t3 - t2) as f64 * 1e-6;
        if round_trip < -TIMESTAMP_ERROR {
            return Err(ReplyOutcome::Absurd);
        }
        let max = self.config.max_round_trip.as_secs_f64();
        if round_trip > max || local > max {
            return Err(ReplyOutcome::TooSlow);
        }
        let round_trip = round_trip.max(0.0);
        // offset = ((t2 − t1) + (t3 − t4)) / 2 with t4 = t1 + local: the whole microseconds
        // exactly, the rest (half a microsecond, half the local interval) as a float.
        let twice = (t2 - t1) + (t3 - t1);
        let whole = twice.div_euclid(2);
        if whole.unsigned_abs() > self.config.max_offset.as_micros() {
            return Err(ReplyOutcome::Absurd);
        }
        let offset_us = i64::try_from(whole).map_err(|_| ReplyOutcome::Absurd)?;
        let offset_frac = twice.rem_euclid(2) as f64 * 0.5e-6 - local / 2.0;
        let skew = self.config.max_skew_ppm * 1e-6;
        Ok(Sample {
            at: self.secs(query.sent.mono) + local / 2.0,
            offset_us,
            offset_frac,
            offset: 0.0,
            radius: round_trip / 2.0 + TIMESTAMP_ERROR + skew * local,
            round_trip,
            round: query.round,
        })
    }

    /// Takes a valid sample into the estimate, or holds it as a possible clock step until
    /// `step_samples` contradicting samples in a row agree with each other.
    pub(super) fn add(&mut self, mut sample: Sample, now: Instant) -> ReplyOutcome {
        sample.offset = sample.relative_to(self.base_us);
        if self.len > 0 {
            let (offset, uncertainty) = self.predict_at(sample.at);
            if (sample.offset - offset).abs() > uncertainty + sample.radius {
                return self.hold(sample, now);
            }
        }
        self.suspects_len = 0;
        self.insert(sample);
        self.refit();
        self.last_used = self.last_used.max(sample.at);
        ReplyOutcome::Used
    }

    /// A sample that contradicts the history: held with the others that agree with it; a
    /// full set is a clock step and replaces the history.
    fn hold(&mut self, sample: Sample, now: Instant) -> ReplyOutcome {
        let held = &self.suspects[..self.suspects_len];
        if !held.iter().all(|h| self.agree(h, &sample)) {
            self.suspects_len = 0;
        }
        self.suspects[self.suspects_len] = sample;
        self.suspects_len += 1;
        if self.suspects_len < self.config.step_samples as usize {
            return ReplyOutcome::Held;
        }
        self.len = 0;
        self.base_us = sample.offset_us;
        let mut newest = sample.at;
        for i in 0..self.suspects_len {
            let mut s = self.suspects[i];
            s.offset = s.relative_to(self.base_us);
            newest = newest.max(s.at);
            self.insert(s);
        }
        self.suspects_len = 0;
        self.refit();
        self.last_used = newest;
        self.stats.clock_steps += 1;
        if self.quick_round_allowed(now) {
            self.start_quick_round(now);
        }
        ReplyOutcome::ClockStepped
    }

    /// The anchor's prediction at `t`, ignoring staleness.
    pub(super) fn predict_at(&self, t: f64) -> (f64, f64) {
        let a = &self.history[self.anchor];
        let dt = t - a.at;
        (
            a.offset + self.drift * dt,
            a.radius + self.drift_error * dt.abs(),
        )
    }

    /// Whether two samples can both hold under the largest allowed drift.
    fn agree(&self, a: &Sample, b: &Sample) -> bool {
        let skew = self.config.max_skew_ppm * 1e-6;
        a.minus(b).abs() <= a.radius + b.radius + skew * (a.at - b.at).abs()
    }

    /// Adds `sample` as its round's best (replacing a worse one), evicting the oldest round
    /// when the window is full. A late sample of a round older than the newest kept is dropped.
    fn insert(&mut self, sample: Sample) {
        if self.len > 0 {
            let last = &mut self.history[self.len - 1];
            let newer = sample.round.wrapping_sub(last.round) as i32;
            if newer == 0 {
                if sample.radius < last.radius {
                    *last = sample;
                }
                return;
            }
            if newer < 0 {
                return;
            }
        }
        if self.len == self.config.window {
            self.history.copy_within(1..self.len, 0);
            self.len -= 1;
        }
        self.history[self.len] = sample;
        self.len += 1;
    }

    /// Recomputes the drift interval from every pair of kept samples, dropping the oldest
    /// samples while they contradict the newer ones, and picks the anchor. Offsets are first
    /// re-expressed relative to the newest sample, so their floating-point values stay small.
    pub(super) fn refit(&mut self) {
        if self.len == 0 {
            return;
        }
        self.base_us = self.history[self.len - 1].offset_us;
        for s in &mut self.history[..self.len] {
            s.offset = s.relative_to(self.base_us);
        }
        let skew = self.config.max_skew_ppm * 1e-6;
        let (mut low, mut high) = (-skew, skew);
        let mut keep_from = self.len - 1;
        for j in (0..self.len - 1).rev() {
            let (mut l, mut h) = (low, high);
            for k in j + 1..self.len {
                if let Some((pl, ph)) = drift_bounds(&self.history[j], &self.history[k]) {
                    l = l.max(pl);
                    h = h.min(ph);
                }
            }
            if l > h {
                break;
            }
            (low, high, keep_from) = (l, h, j);
        }
        if keep_from > 0 {
            self.history.copy_within(keep_from..self.len, 0);
            self.len -= keep_from;
        }
        self.drift = (low + high) / 2.0;
        self.drift_error = (high - low) / 2.0 + self.config.wander_ppm * 1e-6;
        // Every sample's uncertainty grows at the same rate after it, so the smallest at any
        // later time is the smallest `radius − drift_error × at`.
        let e = self.drift_error;
        self.anchor = (0..self.len)
            .min_by(|&x, &y| {
                let (a, b) = (&self.history[x], &self.history[y]);
                (a.radius - e * a.at).total_cmp(&(b.radius - e * b.at))
            })
            .unwrap_or(0);
    }
}

/// The drift interval two samples allow, or `None` if they are too close in time to say much.
pub(super) fn drift_bounds(a: &Sample, b: &Sample) -> Option<(f64, f64)> {
    let (early, late) = if a.at <= b.at { (a, b) } else { (b, a) };
    let span = late.at - early.at;
    if span < MIN_PAIR_SPAN {
        return None;
    }
    let change = late.offset - early.offset;
    let slack = late.radius + early.radius;
    Some(((change - slack) / span, (change + slack) / span))
}
