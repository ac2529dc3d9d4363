//! Analog output messages: clients ask a server to set output channels; the
//! server announces how many channels it has. C++ checks none of these lengths.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};
use super::analog::CHANNEL_MAX;

/// Set one channel, client->server, 16 bytes ([`ChangeRequest`]).
pub const CHANGE_REQUEST: &str = "vrpn_Analog_Output Change_request";
/// Set channels `0..n`, client->server, 8 + 8·n bytes ([`ChangeChannelsRequest`]).
pub const CHANGE_CHANNELS_REQUEST: &str = "vrpn_Analog_Output Change_Channels_request";
/// Number of output channels, server->client, 4 bytes ([`NumChannelsReport`]).
pub const NUM_CHANNELS_REPORT: &str = "vrpn_Analog_Output Num_Channels_report";

/// The analog output type names in C++ registration order (the base class then also registers
/// the local `VRPN_Connection_Got_Connection`).
pub const TYPE_NAMES: &[&str] = &[CHANGE_REQUEST, CHANGE_CHANNELS_REQUEST, NUM_CHANNELS_REPORT];

fixed_payload! {
    /// `vrpn_Analog_Output Change_request`: set one channel. At least 16 bytes.
    pub struct ChangeRequest: at_least {
        /// Channel index.
        pub channel: i32,
        /// Alignment filler as on the wire (0 from C++).
        pub pad: i32,
        /// Requested value.
        pub value: f64,
    }
}

impl ChangeRequest {
    /// A request as the C++ remote builds it (filler = 0).
    pub fn new(channel: i32, value: f64) -> ChangeRequest {
        ChangeRequest {
            channel,
            pad: 0,
            value,
        }
    }
}

fixed_payload! {
    /// `vrpn_Analog_Output Num_Channels_report`: active output channels. At least 4 bytes.
    pub struct NumChannelsReport: at_least {
        /// Number of output channels (the C++ remote accepts 0..=128).
        pub num_channels: i32,
    }
}

/// `vrpn_Analog_Output Change_Channels_request`: values for channels `0..n`.
///
/// Wire layout: i32 n, i32 filler (0), n × f64. The C++ server clamps n to its channel count
/// (at most 128) and reads that many values without a length check; here a negative n is an
/// error, n is clamped to [`CHANNEL_MAX`], and the payload must hold the values read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangeChannelsRequest {
    /// Number of values, `0..=CHANNEL_MAX`.
    pub count: usize,
    /// Alignment filler as on the wire (0 from C++).
    pub pad: i32,
    /// Values for channels `0..count`; the rest is zero.
    pub values: [f64; CHANNEL_MAX],
}

impl Default for ChangeChannelsRequest {
    fn default() -> Self {
        ChangeChannelsRequest {
            count: 0,
            pad: 0,
            values: [0.0; CHANNEL_MAX],
        }
    }
}

impl ChangeChannelsRequest {
    /// A request for at most [`CHANNEL_MAX`] values (the rest is dropped), filler 0.
    pub fn from_slice(values: &[f64]) -> ChangeChannelsRequest {
        let count = values.len().min(CHANNEL_MAX);
        let mut r = ChangeChannelsRequest {
            count,
            ..ChangeChannelsRequest::default()
        };
        r.values[..count].copy_from_slice(&values[..count]);
        r
    }

    /// The requested values.
    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.count.min(CHANNEL_MAX)]
    }

    /// Payload length: 8 + 8·count.
    pub fn encoded_len(&self) -> usize {
        8 + 8 * self.as_slice().len()
    }

    /// Decodes a request (length rule in the type's doc).
    pub fn decode(buf: &[u8]) -> Result<ChangeChannelsRequest> {
        need(buf, 8)?;
        let n = BigEndian::read_i32(&buf[0..4]);
        if n < 0 {
            return Err(WireError::BadValue("analog output channel count"));
        }
        let n = (n as usize).min(CHANNEL_MAX);
        need(buf, 8 + 8 * n)?;
        let mut r = ChangeChannelsRequest {
            count: n,
            pad: BigEndian::read_i32(&buf[4..8]),
            ..ChangeChannelsRequest::default()
        };
        BigEndian::read_f64_into(&buf[8..8 + 8 * n], &mut r.values[..n]);
        Ok(r)
    }

    /// Writes the payload at the start of `out` (at least [`Self::encoded_len`] bytes).
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let values = self.as_slice();
        let len = 8 + 8 * values.len();
        BigEndian::write_i32(&mut out[0..4], values.len() as i32);
        BigEndian::write_i32(&mut out[4..8], self.pad);
        BigEndian::write_f64_into(values, &mut out[8..len]);
        len
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn round_trips() {
        let b = round_trip!(ChangeRequest, ChangeRequest::new(3, 0.5));
        assert_eq!(b, hex("00000003 00000000 3fe0000000000000"));
        let b = round_trip!(NumChannelsReport, NumChannelsReport { num_channels: 16 });
        assert_eq!(b, hex("00000010"));

        for n in [0usize, 1, 3, CHANNEL_MAX] {
            let vals: Vec<f64> = (0..n).map(|i| i as f64 / 3.0).collect();
            let r = ChangeChannelsRequest::from_slice(&vals);
            let mut buf = [0u8; 8 + 8 * CHANNEL_MAX];
            let len = r.encode(&mut buf);
            assert_eq!(len, r.encoded_len());
            let back = ChangeChannelsRequest::decode(&buf[..len]).unwrap();
            assert_eq!(back, r);
            for cut in 0..len {
                assert!(ChangeChannelsRequest::decode(&buf[..cut]).is_err());
            }
        }
    }

    #[test]
    fn change_channels_layout_and_limits() {
        let r = ChangeChannelsRequest::from_slice(&[1.0, -2.0]);
        let mut buf = [0u8; 24];
        r.encode(&mut buf);
        assert_eq!(
            buf.to_vec(),
            hex("00000002 00000000 3ff0000000000000 c000000000000000")
        );
        assert!(ChangeChannelsRequest::decode(&hex("ffffffff00000000")).is_err());
        let mut big = vec![0u8; 8 + 8 * 200];
        big[3] = 200;
        assert_eq!(
            ChangeChannelsRequest::decode(&big).unwrap().count,
            CHANNEL_MAX
        );
    }
}
