//! Function generator messages (`vrpn_FunctionGenerator`): a remote sets the function of
//! each channel, the sample rate, starts and stops generation; the server replies to each.
//!
//! A channel's function is an i32 code, 0 for the null function (zeros) and 1 for a script,
//! which is followed by a u32 length and the script's bytes (no NUL). Booleans are 16-bit
//! (`vrpn_bool`).

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};

/// Set a channel's function, remote->server ([`ChannelMessage`]).
pub const CHANNEL: &str = "vrpn_FunctionGenerator channel";
/// Ask for a channel's function, remote->server, 4 bytes ([`ChannelNumber`]).
pub const CHANNEL_REQUEST: &str = "vrpn_FunctionGenerator channel request";
/// Ask for every channel's function, remote->server, empty.
pub const ALL_CHANNEL_REQUEST: &str = "vrpn_FunctionGenerator all channel request";
/// Ask for a sample rate, remote->server, 4 bytes ([`SampleRate`]).
pub const SAMPLE_RATE: &str = "vrpn_FunctionGenerator sample rate";
/// Start generating, remote->server, empty.
pub const START: &str = "vrpn_FunctionGenerator start";
/// Stop generating, remote->server, empty.
pub const STOP: &str = "vrpn_FunctionGenerator stop";
/// A channel's function, server->remote ([`ChannelMessage`]).
pub const CHANNEL_REPLY: &str = "vrpn_FunctionGenerator channel reply";
/// Whether generation started, server->remote, 2 bytes ([`Flag`]).
pub const START_REPLY: &str = "vrpn_FunctionGenerator start reply";
/// Whether generation stopped, server->remote, 2 bytes ([`Flag`]).
pub const STOP_REPLY: &str = "vrpn_FunctionGenerator stop reply";
/// The sample rate in force, server->remote, 4 bytes ([`SampleRate`]).
pub const SAMPLE_RATE_REPLY: &str = "vrpn_FunctionGenerator sample rate reply";
/// Ask what the script interpreter is, remote->server, empty.
pub const INTERPRETER_REQUEST: &str = "vrpn_FunctionGenerator interpreter-description request";
/// The interpreter's description, server->remote ([`Description`]).
pub const INTERPRETER_REPLY: &str = "vrpn_FunctionGenerator interpreter-description reply";
/// An error, server->remote, 8 bytes ([`ErrorReport`]).
pub const ERROR: &str = "vrpn_FunctionGenerator error report";

/// The function generator type names in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[
    CHANNEL,
    CHANNEL_REQUEST,
    ALL_CHANNEL_REQUEST,
    SAMPLE_RATE,
    START,
    STOP,
    INTERPRETER_REQUEST,
    CHANNEL_REPLY,
    START_REPLY,
    STOP_REPLY,
    SAMPLE_RATE_REPLY,
    INTERPRETER_REPLY,
    ERROR,
];

/// Channels of a function generator (`vrpn_FUNCTION_CHANNELS_MAX`).
pub const MAX_CHANNELS: usize = 128;

/// Code of the null function.
pub const FUNCTION_NULL: i32 = 0;
/// Code of a script function.
pub const FUNCTION_SCRIPT: i32 = 1;

/// A channel's function, borrowing a script's text from the payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Function<'a> {
    /// Generates zeros (code 0).
    Null,
    /// A script for the server's interpreter (code 1).
    Script(&'a [u8]),
}

impl<'a> Function<'a> {
    /// Bytes on the wire.
    pub fn encoded_len(&self) -> usize {
        match self {
            Function::Null => 4,
            Function::Script(s) => 8 + s.len(),
        }
    }

    /// Decodes a function from the start of `buf`; returns it and the bytes it took.
    pub fn decode(buf: &'a [u8]) -> Result<(Function<'a>, usize)> {
        need(buf, 4)?;
        match BigEndian::read_i32(&buf[0..4]) {
            FUNCTION_NULL => Ok((Function::Null, 4)),
            FUNCTION_SCRIPT => {
                need(buf, 8)?;
                let n = BigEndian::read_u32(&buf[4..8]) as usize;
                if buf.len() - 8 < n {
                    return Err(WireError::Truncated {
                        needed: 8usize.saturating_add(n),
                        available: buf.len(),
                    });
                }
                Ok((Function::Script(&buf[8..8 + n]), 8 + n))
            }
            _ => Err(WireError::BadValue("function generator function code")),
        }
    }

    /// Writes the function at the start of `out`; returns its length.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        match self {
            Function::Null => {
                BigEndian::write_i32(&mut out[0..4], FUNCTION_NULL);
                4
            }
            Function::Script(s) => {
                BigEndian::write_i32(&mut out[0..4], FUNCTION_SCRIPT);
                BigEndian::write_u32(&mut out[4..8], s.len() as u32);
                out[8..8 + s.len()].copy_from_slice(s);
                8 + s.len()
            }
        }
    }
}

/// `channel` and `channel reply`: u32 channel, then the [`Function`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChannelMessage<'a> {
    /// Channel number.
    pub channel: u32,
    /// Its function.
    pub function: Function<'a>,
}

impl<'a> ChannelMessage<'a> {
    /// Decodes the payload (bytes after the function are ignored).
    pub fn decode(buf: &'a [u8]) -> Result<ChannelMessage<'a>> {
        need(buf, 4)?;
        let (function, _) = Function::decode(&buf[4..])?;
        Ok(ChannelMessage {
            channel: BigEndian::read_u32(&buf[0..4]),
            function,
        })
    }

    /// Payload length.
    pub fn encoded_len(&self) -> usize {
        4 + self.function.encoded_len()
    }

    /// Writes the payload at the start of `out` (at least [`Self::encoded_len`] bytes).
    pub fn encode(&self, out: &mut [u8]) -> usize {
        BigEndian::write_u32(&mut out[0..4], self.channel);
        4 + self.function.encode(&mut out[4..])
    }
}

fixed_payload! {
    /// `channel request`: which channel. At least 4 bytes.
    pub struct ChannelNumber: at_least {
        /// Channel number.
        pub channel: u32,
    }
}

fixed_payload! {
    /// `sample rate` and `sample rate reply`: samples per second. At least 4 bytes.
    pub struct SampleRate: at_least {
        /// Samples per second.
        pub rate: f32,
    }
}

fixed_payload! {
    /// `start reply` and `stop reply`: a 16-bit boolean. At least 2 bytes.
    pub struct Flag: at_least {
        /// Non-zero: yes.
        pub value: i16,
    }
}

fixed_payload! {
    /// `error report`: what went wrong, on which channel. At least 8 bytes.
    pub struct ErrorReport: at_least {
        /// 0 none, 1 interpreter error, 2 taking too long, 3 wrong number of values,
        /// 4 values out of range.
        pub error: i32,
        /// The channel concerned.
        pub channel: i32,
    }
}

/// `interpreter-description reply`: i32 length, then the description's bytes (no NUL).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Description<'a> {
    /// The description.
    pub text: &'a [u8],
}

impl<'a> Description<'a> {
    /// Decodes the payload; a negative length or one beyond the payload is an error.
    pub fn decode(buf: &'a [u8]) -> Result<Description<'a>> {
        need(buf, 4)?;
        let n = BigEndian::read_i32(&buf[0..4]);
        if n < 0 {
            return Err(WireError::BadValue("interpreter description length"));
        }
        need(&buf[4..], n as usize)?;
        Ok(Description {
            text: &buf[4..4 + n as usize],
        })
    }

    /// Payload length.
    pub fn encoded_len(&self) -> usize {
        4 + self.text.len()
    }

    /// Writes the payload at the start of `out`.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        BigEndian::write_i32(&mut out[0..4], self.text.len() as i32);
        out[4..4 + self.text.len()].copy_from_slice(self.text);
        self.encoded_len()
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn layouts() {
        let mut buf = [0u8; 64];
        let m = ChannelMessage {
            channel: 2,
            function: Function::Script(b"sin(t)"),
        };
        let n = m.encode(&mut buf);
        assert_eq!(n, m.encoded_len());
        assert_eq!(
            &buf[..n],
            &hex("00000002 00000001 00000006 73696e287429")[..]
        );
        assert_eq!(ChannelMessage::decode(&buf[..n]).unwrap(), m);
        for cut in 0..n {
            assert!(ChannelMessage::decode(&buf[..cut]).is_err());
        }
        let m = ChannelMessage {
            channel: 0,
            function: Function::Null,
        };
        let n = m.encode(&mut buf);
        assert_eq!(&buf[..n], &hex("00000000 00000000")[..]);
        assert!(ChannelMessage::decode(&hex("00000000 00000002")).is_err());
        // A script length beyond the payload.
        assert!(ChannelMessage::decode(&hex("00000000 00000001 ffffffff 00")).is_err());

        let b = round_trip!(ChannelNumber, ChannelNumber { channel: 5 });
        assert_eq!(b, hex("00000005"));
        let b = round_trip!(SampleRate, SampleRate { rate: 1000.0 });
        assert_eq!(b, hex("447a0000"));
        let b = round_trip!(Flag, Flag { value: 1 });
        assert_eq!(b, hex("0001"));
        let b = round_trip!(
            ErrorReport,
            ErrorReport {
                error: 1,
                channel: 3
            }
        );
        assert_eq!(b, hex("00000001 00000003"));

        let d = Description { text: b"none" };
        let n = d.encode(&mut buf);
        assert_eq!(&buf[..n], &hex("00000004 6e6f6e65")[..]);
        assert_eq!(Description::decode(&buf[..n]).unwrap(), d);
        assert!(Description::decode(&hex("ffffffff")).is_err());
        assert!(Description::decode(&hex("00000009 6e6f")).is_err());
    }
}
