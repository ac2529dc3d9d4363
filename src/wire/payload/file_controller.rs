//! `vrpn_File_Controller`: messages that control a log replay (C++ `vrpn_File_Connection`
//! answers them), from the sender `vrpn File Controller`.
//!
//! * set replay rate: a big-endian `f32` (4 bytes);
//! * reset: no payload;
//! * play to time: a C `struct timeval` **in the sender's own memory layout** (C++ copies the
//!   struct raw): on 64-bit Linux and macOS, 16 bytes, seconds then microseconds, each a
//!   little-endian `i64` on x86-64 and ARM; on 32-bit hosts, 8 bytes of two `i32`. The time is
//!   elapsed time since the first message of the log.
//!
//! A 64-bit C++ replay reads that payload as two 32-bit words, so from a 64-bit sender it gets
//! the seconds right (below 2^31) and always zero microseconds; this crate reads both layouts
//! exactly.

use byteorder::{BigEndian, ByteOrder, LittleEndian};

use super::super::{need, Result, WireError};
use crate::time::TimeVal;

/// The sender of the three messages.
pub const SENDER: &str = "vrpn File Controller";
/// Sets the replay rate.
pub const SET_REPLAY_RATE: &str = "vrpn_File set_replay_rate";
/// Back to the start of the log.
pub const RESET: &str = "vrpn_File reset";
/// Plays everything up to an elapsed time.
pub const PLAY_TO_TIME: &str = "vrpn_File play_to_time";

/// The types in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[SET_REPLAY_RATE, RESET, PLAY_TO_TIME];

/// Length of a set-replay-rate payload.
pub const RATE_LEN: usize = 4;
/// Length of a play-to-time payload as a 64-bit sender writes it (and as this crate does).
pub const PLAY_TO_TIME_LEN: usize = 16;

/// Writes a set-replay-rate payload.
pub fn encode_rate(out: &mut [u8], rate: f32) -> usize {
    BigEndian::write_f32(&mut out[..4], rate);
    RATE_LEN
}

/// Reads a set-replay-rate payload (C++ reads the first four bytes).
pub fn decode_rate(payload: &[u8]) -> Result<f32> {
    need(payload, RATE_LEN)?;
    Ok(BigEndian::read_f32(&payload[..4]))
}

/// Writes a play-to-time payload as a 64-bit little-endian C++ sender does.
pub fn encode_play_to_time(out: &mut [u8], elapsed: TimeVal) -> usize {
    LittleEndian::write_i64(&mut out[0..8], elapsed.sec);
    LittleEndian::write_i64(&mut out[8..16], elapsed.usec);
    PLAY_TO_TIME_LEN
}

/// Reads a play-to-time payload of either layout (16 bytes: two `i64`; 8 bytes: two `i32`,
/// little-endian).
pub fn decode_play_to_time(payload: &[u8]) -> Result<TimeVal> {
    let (sec, usec) = match payload.len() {
        16 => (
            LittleEndian::read_i64(&payload[0..8]),
            LittleEndian::read_i64(&payload[8..16]),
        ),
        8 => (
            i64::from(LittleEndian::read_i32(&payload[0..4])),
            i64::from(LittleEndian::read_i32(&payload[4..8])),
        ),
        _ => return Err(WireError::BadValue("play_to_time payload length")),
    };
    if !(0..1_000_000).contains(&usec) || sec < 0 {
        return Err(WireError::BadValue("play_to_time time"));
    }
    Ok(TimeVal::new(sec, usec))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_is_a_big_endian_float() {
        let mut buf = [0u8; 4];
        assert_eq!(encode_rate(&mut buf, 2.0), 4);
        assert_eq!(buf, [0x40, 0, 0, 0]);
        assert_eq!(decode_rate(&buf).unwrap(), 2.0);
        assert!(decode_rate(&buf[..3]).is_err());
    }

    #[test]
    fn play_to_time_is_a_raw_timeval() {
        // What C++ `play_to_time({30, 250000})` sends from x86-64.
        let mut buf = [0u8; 16];
        encode_play_to_time(&mut buf, TimeVal::new(30, 250_000));
        assert_eq!(
            buf,
            [30, 0, 0, 0, 0, 0, 0, 0, 0x90, 0xd0, 0x03, 0, 0, 0, 0, 0]
        );
        assert_eq!(
            decode_play_to_time(&buf).unwrap(),
            TimeVal::new(30, 250_000)
        );
        // A 32-bit sender's layout.
        let short = [30, 0, 0, 0, 0x90, 0xd0, 0x03, 0];
        assert_eq!(
            decode_play_to_time(&short).unwrap(),
            TimeVal::new(30, 250_000)
        );
        for bad in [&buf[..15], &[0u8; 12][..], &[0u8; 0][..]] {
            assert!(decode_play_to_time(bad).is_err());
        }
        let mut neg = buf;
        LittleEndian::write_i64(&mut neg[8..16], 1_000_000);
        assert!(decode_play_to_time(&neg).is_err());
    }
}
