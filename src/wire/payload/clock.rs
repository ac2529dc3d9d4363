//! Clock-synchronisation messages: a query and its reply, carrying NTP's timestamps so that the
//! querier can estimate the offset between its clock and the responder's (see
//! [`crate::proto::clock`] for the estimator).
//!
//! # The exchange
//!
//! The querier sends a [`Query`] stamped with its own clock when sending (`t1`). The responder
//! answers with a [`Reply`] that echoes the exchange id and `t1` and adds its own clock when the
//! query arrived (`t2`) and when the reply leaves (`t3`). The querier reads its clock when the
//! reply arrives (`t4`). Then, with `offset = responder clock − querier clock`:
//!
//! ```text
//! offset     ≈ ((t2 − t1) + (t3 − t4)) / 2
//! round trip =  (t4 − t1) − (t3 − t2)
//! ```
//!
//! and the true offset lies within half the round trip of the estimate, however the delay is
//! split between the two directions.
//!
//! # Why not the VRPN 06 clock messages
//!
//! VRPN 06 had `vrpn_Clock query` / `vrpn_Clock reply`; 07.x removed them. These messages use new
//! names in a `vrpn_Rust` namespace and a new layout because the old one cannot give an accurate
//! estimate or a sound bound:
//!
//! * the old reply carries one responder timestamp, so the responder's processing time counts
//!   as network delay and the offset rests on "the reply was made half-way through";
//!   here the reply carries both `t2` and `t3`;
//! * the old reply went to every client of the server (matched by an id taken from the
//!   microseconds of a clock reading); here a reply answers one query and is matched on the id
//!   *and* the echoed `t1`;
//! * the old payload held 32-bit seconds (overflow in 2038) and a sync "kind"; here every time
//!   is a 64-bit count of microseconds since 1970;
//! * reusing the old names with a different layout would mislead any tool that still knows it.
//!
//! A C++ 07.x peer has no handler for these types: it registers the unknown names, echoes their
//! descriptions and ignores the messages, so a querier facing it simply never gets a reply.
//!
//! # Layout
//!
//! Big-endian like every VRPN payload; both lengths are multiples of 8, so no padding follows.
//!
//! | Offset | [`Query`] (16 bytes)            | [`Reply`] (32 bytes)              |
//! |--------|---------------------------------|-----------------------------------|
//! | 0      | u32 version = [`VERSION`]       | u32 version = [`VERSION`]         |
//! | 4      | u32 exchange id                 | u32 exchange id (echoed)          |
//! | 8      | i64 `t1`, querier µs since 1970 | i64 `t1` (echoed)                 |
//! | 16     |                                 | i64 `t2`, responder µs since 1970 |
//! | 24     |                                 | i64 `t3`, responder µs since 1970 |
//!
//! Decoders never panic. They refuse a short payload, a version other than [`VERSION`] and a
//! timestamp beyond ±[`MAX_TIME_MICROS`], and accept a longer payload, ignoring its tail (room for compatible additions). A receiver must
//! *ignore* a message that does not decode — it is foreign or from a future version — and never
//! drop the peer for it.

use byteorder::{BigEndian, ByteOrder};

use crate::time::TimeVal;
use crate::wire::{self, WireError};

/// Type name of [`Query`] messages.
pub const QUERY: &str = "vrpn_Rust ClockSync query";
/// Type name of [`Reply`] messages.
pub const REPLY: &str = "vrpn_Rust ClockSync reply";
/// Sender name under which both sides send queries and replies (one per connection, not per
/// device: the clocks belong to the hosts, not to the devices).
pub const SENDER: &str = "vrpn_Rust ClockSync";
/// Every clock-sync type name, queries first.
pub const TYPE_NAMES: &[&str] = &[QUERY, REPLY];

/// Layout version carried in the first word of both payloads. A payload with another version is
/// refused by the decoders (and so ignored by the receiver).
pub const VERSION: u32 = 1;

/// Largest timestamp magnitude a decoder accepts, in microseconds (2^62 µs, about 146 000
/// years): anything beyond is absurd, and refusing it keeps every later sum and difference of
/// two timestamps far from `i64` overflow.
pub const MAX_TIME_MICROS: i64 = 1 << 62;

/// Reads a timestamp stored as signed microseconds since 1970, refusing absurd magnitudes.
fn read_time(buf: &[u8]) -> wire::Result<TimeVal> {
    let us = BigEndian::read_i64(&buf[..8]);
    if !(-MAX_TIME_MICROS..=MAX_TIME_MICROS).contains(&us) {
        return Err(WireError::BadValue("clock sync timestamp"));
    }
    Ok(TimeVal::from_micros(us))
}

/// Writes a timestamp as signed microseconds since 1970 (saturating for absurd values rather
/// than overflowing).
fn write_time(t: TimeVal, buf: &mut [u8]) {
    let us = t.sec.saturating_mul(1_000_000).saturating_add(t.usec);
    BigEndian::write_i64(&mut buf[..8], us);
}

/// Checks the length and the version word shared by both payloads.
fn check_header(buf: &[u8], len: usize) -> wire::Result<()> {
    wire::need(buf, len)?;
    if BigEndian::read_u32(&buf[..4]) != VERSION {
        return Err(WireError::BadValue("clock sync version"));
    }
    Ok(())
}

/// `vrpn_Rust ClockSync query`: "what does your clock say?", querier → responder.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Query {
    /// Exchange id chosen by the querier, echoed in the reply.
    pub id: u32,
    /// `t1`: the querier's wall clock when the query was sent.
    pub query_sent: TimeVal,
}

impl Query {
    /// Payload length in bytes.
    pub const LEN: usize = 16;

    /// Decodes the payload: at least [`Query::LEN`] bytes (a longer tail is ignored) and
    /// version [`VERSION`], else an error that the receiver ignores.
    pub fn decode(buf: &[u8]) -> wire::Result<Query> {
        check_header(buf, Self::LEN)?;
        Ok(Query {
            id: BigEndian::read_u32(&buf[4..8]),
            query_sent: read_time(&buf[8..16])?,
        })
    }

    /// Writes the payload at the start of `out` (at least `LEN` bytes); returns `LEN`.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        BigEndian::write_u32(&mut out[..4], VERSION);
        BigEndian::write_u32(&mut out[4..8], self.id);
        write_time(self.query_sent, &mut out[8..16]);
        Self::LEN
    }
}

/// `vrpn_Rust ClockSync reply`: the answer to one [`Query`], responder → querier.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reply {
    /// The query's exchange id, echoed.
    pub id: u32,
    /// `t1`, echoed from the query (the querier matches on it as well as on the id).
    pub query_sent: TimeVal,
    /// `t2`: the responder's wall clock when the query arrived.
    pub query_received: TimeVal,
    /// `t3`: the responder's wall clock when the reply was sent.
    pub reply_sent: TimeVal,
}

impl Reply {
    /// Payload length in bytes.
    pub const LEN: usize = 32;

    /// The reply to `query` from a responder whose clock read `received` when the query
    /// arrived and `sending` when the reply is packed.
    ///
    /// For the querier's bound to hold, `received` must be read no earlier than the query was
    /// read from the network, and `sending` no later than the reply is written to it.
    pub fn answer(query: &Query, received: TimeVal, sending: TimeVal) -> Reply {
        Reply {
            id: query.id,
            query_sent: query.query_sent,
            query_received: received,
            reply_sent: sending,
        }
    }

    /// Decodes the payload: at least [`Reply::LEN`] bytes (a longer tail is ignored) and
    /// version [`VERSION`], else an error that the receiver ignores.
    pub fn decode(buf: &[u8]) -> wire::Result<Reply> {
        check_header(buf, Self::LEN)?;
        Ok(Reply {
            id: BigEndian::read_u32(&buf[4..8]),
            query_sent: read_time(&buf[8..16])?,
            query_received: read_time(&buf[16..24])?,
            reply_sent: read_time(&buf[24..32])?,
        })
    }

    /// Writes the payload at the start of `out` (at least `LEN` bytes); returns `LEN`.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        BigEndian::write_u32(&mut out[..4], VERSION);
        BigEndian::write_u32(&mut out[4..8], self.id);
        write_time(self.query_sent, &mut out[8..16]);
        write_time(self.query_received, &mut out[16..24]);
        write_time(self.reply_sent, &mut out[24..32]);
        Self::LEN
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn names_fit_a_cpp_peer_and_do_not_reuse_the_historic_ones() {
        for name in TYPE_NAMES.iter().chain([&SENDER]) {
            assert!(name.len() <= wire::MAX_NAME_LEN, "{name}");
            assert!(name.starts_with("vrpn_Rust "), "{name}");
        }
        assert!(!TYPE_NAMES.contains(&"vrpn_Clock query"));
        assert!(!TYPE_NAMES.contains(&"vrpn_Clock reply"));
        assert_ne!(QUERY, REPLY);
    }

    #[test]
    fn query_golden_bytes() {
        let q = Query {
            id: 0x0102_0304,
            query_sent: TimeVal::new(1, 2),
        };
        let bytes = round_trip!(Query, q);
        assert_eq!(bytes, hex("00000001 01020304 00000000000F4242"));
    }

    #[test]
    fn reply_golden_bytes_and_answer() {
        let q = Query {
            id: 7,
            query_sent: TimeVal::new(1_700_000_000, 5),
        };
        let r = Reply::answer(&q, TimeVal::new(1_700_010_800, 900_000), TimeVal::new(0, 1));
        assert_eq!(r.id, 7);
        assert_eq!(r.query_sent, q.query_sent);
        let bytes = round_trip!(Reply, r);
        // 1_700_000_000_000_005 µs = 0x0006_0A24_181E_4005.
        assert_eq!(
            bytes,
            hex("00000001 00000007 00060A24181E4005 00060A269BE6E7A0 0000000000000001")
        );
    }

    #[test]
    fn times_before_1970_and_far_future_survive() {
        round_trip!(
            Query,
            Query {
                id: u32::MAX,
                query_sent: TimeVal::new(-5, 250_000),
            }
        );
        round_trip!(
            Reply,
            Reply {
                id: 0,
                query_sent: TimeVal::new(4_102_444_800, 0), // 2100, past the 32-bit limit
                query_received: TimeVal::from_micros(MAX_TIME_MICROS),
                reply_sent: TimeVal::from_micros(-MAX_TIME_MICROS),
            }
        );
    }

    #[test]
    fn absurd_times_are_refused_never_a_panic() {
        let mut buf = [0u8; Reply::LEN];
        Reply::default().encode(&mut buf);
        for (at, us) in [(8, i64::MIN), (16, i64::MAX), (24, MAX_TIME_MICROS + 1)] {
            let mut bad = buf;
            BigEndian::write_i64(&mut bad[at..at + 8], us);
            assert_eq!(
                Reply::decode(&bad),
                Err(WireError::BadValue("clock sync timestamp"))
            );
        }
        // An absurd local value saturates on encoding instead of overflowing, and is then
        // refused by the peer's decoder.
        let q = Query {
            id: 1,
            query_sent: TimeVal {
                sec: i64::MAX,
                usec: 0,
            },
        };
        let mut out = [0u8; Query::LEN];
        q.encode(&mut out);
        assert_eq!(BigEndian::read_i64(&out[8..]), i64::MAX);
        assert!(Query::decode(&out).is_err());
    }

    #[test]
    fn foreign_versions_are_refused_and_tails_ignored() {
        let r = Reply {
            id: 3,
            query_sent: TimeVal::new(10, 0),
            query_received: TimeVal::new(20, 0),
            reply_sent: TimeVal::new(21, 0),
        };
        let mut buf = [0u8; 40];
        r.encode(&mut buf);
        // A longer payload (a compatible future addition) decodes to the same reply.
        assert_eq!(Reply::decode(&buf).unwrap(), r);
        for version in [0u32, 2, 0x10, u32::MAX] {
            let mut bad = buf;
            BigEndian::write_u32(&mut bad[..4], version);
            assert_eq!(
                Reply::decode(&bad),
                Err(WireError::BadValue("clock sync version"))
            );
            assert!(Query::decode(&bad[..16]).is_err());
        }
        // The historic 06 query (12 bytes: 0x10, id, kind) is refused, not misread.
        assert!(Query::decode(&hex("00000010 00000001 00000002")).is_err());
    }
}
