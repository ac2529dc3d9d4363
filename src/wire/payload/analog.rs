//! Analog messages: the full channel vector.
//!
//! Wire layout of `vrpn_Analog Channel`: the channel count n **as an f64**, then n × f64.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};
use super::f64_at;

/// The channel report, server->client, 8 + 8·n bytes ([`Channels`]).
pub const CHANNEL: &str = "vrpn_Analog Channel";

/// Every analog type name in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[CHANNEL];

/// Most channels per device (`vrpn_CHANNEL_MAX`).
pub const CHANNEL_MAX: usize = 128;

/// Payload length of a report with `n` channels.
#[inline]
pub const fn channels_len(n: usize) -> usize {
    8 + 8 * n
}

/// Reads the count of a Channel payload the way the C++ remote does (`(long)` of the double),
/// clamped to [`CHANNEL_MAX`] (a larger count would overrun the C++ arrays); NaN and negative counts are errors.
fn read_count(buf: &[u8]) -> Result<usize> {
    need(buf, 8)?;
    let n = BigEndian::read_f64(&buf[0..8]);
    if n.is_nan() || n < 0.0 {
        return Err(WireError::BadValue("analog channel count"));
    }
    Ok((n.trunc().min(CHANNEL_MAX as f64)) as usize)
}

/// Decodes a Channel payload into `out`; returns the channel count.
///
/// The count is clamped to [`CHANNEL_MAX`] and to `out.len()`; only that many values are read,
/// and the payload must hold them (C++ checks no length at all).
pub fn decode_channels_into(buf: &[u8], out: &mut [f64]) -> Result<usize> {
    let n = read_count(buf)?.min(out.len());
    need(buf, channels_len(n))?;
    BigEndian::read_f64_into(&buf[8..channels_len(n)], &mut out[..n]);
    Ok(n)
}

/// Writes a Channel payload for `values` (at most [`CHANNEL_MAX`] are sent); returns its length.
/// `out` must hold [`channels_len`]`(values.len())` bytes.
pub fn encode_channels(values: &[f64], out: &mut [u8]) -> usize {
    let values = &values[..values.len().min(CHANNEL_MAX)];
    let len = channels_len(values.len());
    BigEndian::write_f64(&mut out[0..8], values.len() as f64);
    BigEndian::write_f64_into(values, &mut out[8..len]);
    len
}

/// A decoded `vrpn_Analog Channel` report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Channels {
    /// Number of channels, `0..=CHANNEL_MAX`.
    pub count: usize,
    /// Values of channels `0..count`; the rest is zero.
    pub values: [f64; CHANNEL_MAX],
}

impl Default for Channels {
    fn default() -> Self {
        Channels {
            count: 0,
            values: [0.0; CHANNEL_MAX],
        }
    }
}

impl Channels {
    /// Builds a report from at most [`CHANNEL_MAX`] values (the rest is dropped).
    pub fn from_slice(values: &[f64]) -> Channels {
        let count = values.len().min(CHANNEL_MAX);
        let mut c = Channels {
            count,
            ..Channels::default()
        };
        c.values[..count].copy_from_slice(&values[..count]);
        c
    }

    /// The values of channels `0..count`.
    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.count.min(CHANNEL_MAX)]
    }

    /// Payload length: 8 + 8·count.
    pub fn encoded_len(&self) -> usize {
        channels_len(self.as_slice().len())
    }

    /// Decodes a report (rules of [`decode_channels_into`]).
    pub fn decode(buf: &[u8]) -> Result<Channels> {
        let mut c = Channels::default();
        c.count = decode_channels_into(buf, &mut c.values)?;
        Ok(c)
    }

    /// Writes the payload at the start of `out` (at least [`Channels::encoded_len`] bytes).
    pub fn encode(&self, out: &mut [u8]) -> usize {
        encode_channels(self.as_slice(), out)
    }

    /// Channel `i`, read straight from a payload without decoding the rest (`None` when the
    /// payload does not hold it).
    pub fn peek(buf: &[u8], i: usize) -> Option<f64> {
        let n = read_count(buf).ok()?;
        (i < n && buf.len() >= channels_len(i + 1)).then(|| f64_at(buf, i + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::hex;
    use super::*;

    #[test]
    fn round_trips() {
        for n in [0usize, 1, 2, 5, CHANNEL_MAX] {
            let vals: Vec<f64> = (0..n).map(|i| i as f64 * -0.25 + 1e-300).collect();
            let c = Channels::from_slice(&vals);
            let mut buf = [0u8; channels_len(CHANNEL_MAX)];
            let len = c.encode(&mut buf);
            assert_eq!(len, channels_len(n));
            assert_eq!(c.encoded_len(), len);
            let back = Channels::decode(&buf[..len]).unwrap();
            assert_eq!(back.as_slice(), &vals[..]);
            for cut in 0..len {
                assert!(Channels::decode(&buf[..cut]).is_err());
            }
        }
    }

    #[test]
    fn counts_are_clamped_or_refused() {
        let mut buf = vec![0u8; channels_len(200)];
        BigEndian::write_f64(&mut buf[0..8], 200.0);
        assert_eq!(Channels::decode(&buf).unwrap().count, CHANNEL_MAX);
        BigEndian::write_f64(&mut buf[0..8], 2.9);
        assert_eq!(Channels::decode(&buf).unwrap().count, 2);
        BigEndian::write_f64(&mut buf[0..8], -1.0);
        assert!(Channels::decode(&buf).is_err());
        BigEndian::write_f64(&mut buf[0..8], f64::NAN);
        assert!(Channels::decode(&buf).is_err());
        let mut small = [0.0f64; 1];
        BigEndian::write_f64(&mut buf[0..8], 3.0);
        assert_eq!(decode_channels_into(&buf, &mut small).unwrap(), 1);
    }

    #[test]
    fn golden_joylin_channels() {
        // button_analog_dial: a joystick driver's two axes, over UDP.
        let p = hex("4000000000000000bfddd1bba37746efbfd194232846508d");
        let c = Channels::decode(&p).unwrap();
        assert_eq!(c.as_slice(), &[-0.46592608417004916, -0.27466658528397475]);
        assert_eq!(Channels::peek(&p, 1), Some(-0.27466658528397475));
        assert_eq!(Channels::peek(&p, 2), None);
        let mut out = [0u8; 24];
        assert_eq!(c.encode(&mut out), 24);
        assert_eq!(out.to_vec(), p);
    }
}
