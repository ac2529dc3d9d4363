//! Button messages: edges, the full state vector, mode requests and alerts.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};

/// One button changed, server->client, 8 bytes ([`Change`]).
pub const CHANGE: &str = "vrpn_Button Change";
/// All button states, server->client, 4 + 4·n bytes ([`States`]).
pub const STATES: &str = "vrpn_Button States";
/// Mode request, client->server, 8 bytes ([`Admin`]).
pub const ADMIN: &str = "vrpn_Button Admin";
/// Toggle alert, server->client, 8 bytes ([`Alert`]); registered only by servers.
pub const ALERT: &str = "vrpn_Button Alert";

/// The types every Button object registers, in C++ order. Servers (`vrpn_Button_Filter`)
/// register [`ALERT`] afterwards, after the base-class types.
pub const TYPE_NAMES: &[&str] = &[CHANGE, STATES, ADMIN];

/// Most buttons per device (`vrpn_BUTTON_MAX_BUTTONS`).
pub const MAX_BUTTONS: usize = 256;
/// Admin mode: momentary button.
pub const MOMENTARY: i32 = 10;
/// Admin mode / alert event: toggle, now off.
pub const TOGGLE_OFF: i32 = 20;
/// Admin mode / alert event: toggle, now on.
pub const TOGGLE_ON: i32 = 21;
/// Admin button index meaning "every button".
pub const ALL_ID: i32 = -99;
/// Button released.
pub const OFF: i32 = 0;
/// Button pressed.
pub const ON: i32 = 1;

fixed_payload! {
    /// `vrpn_Button Change`: one button's new state. Exact length 8, as the C++ remote checks.
    pub struct Change: exact {
        /// Button index, 0-based.
        pub button: i32,
        /// New state, [`OFF`] or [`ON`].
        pub state: i32,
    }
}

fixed_payload! {
    /// `vrpn_Button Admin`: set a button's mode. C++ does not check the length (≥ 8 here).
    pub struct Admin: at_least {
        /// Button index, or [`ALL_ID`].
        pub button: i32,
        /// [`MOMENTARY`], [`TOGGLE_OFF`] or [`TOGGLE_ON`].
        pub mode: i32,
    }
}

fixed_payload! {
    /// `vrpn_Button Alert`: a toggle button changed mode. At least 8 bytes.
    pub struct Alert: at_least {
        /// Button index.
        pub button: i32,
        /// [`TOGGLE_OFF`] or [`TOGGLE_ON`].
        pub event: i32,
    }
}

/// `vrpn_Button States`: the physical state of every button.
///
/// Wire layout: i32 n, then n × i32. C++ trusts n without a length check; here n must be
/// `0..=256` and the payload must hold all n states (a longer payload is accepted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct States {
    /// Number of buttons, `0..=MAX_BUTTONS`.
    pub count: usize,
    /// States of buttons `0..count`; the rest is zero.
    pub states: [i32; MAX_BUTTONS],
}

impl Default for States {
    fn default() -> Self {
        States {
            count: 0,
            states: [0; MAX_BUTTONS],
        }
    }
}

impl States {
    /// Builds a message from a slice of at most [`MAX_BUTTONS`] states (the rest is dropped).
    pub fn from_slice(states: &[i32]) -> States {
        let count = states.len().min(MAX_BUTTONS);
        let mut s = States {
            count,
            ..States::default()
        };
        s.states[..count].copy_from_slice(&states[..count]);
        s
    }

    /// The states of buttons `0..count`.
    pub fn as_slice(&self) -> &[i32] {
        &self.states[..self.count.min(MAX_BUTTONS)]
    }

    /// Payload length: 4 + 4·count.
    pub fn encoded_len(&self) -> usize {
        4 + 4 * self.as_slice().len()
    }

    /// Decodes a States payload (see the type's doc for the length rule).
    pub fn decode(buf: &[u8]) -> Result<States> {
        need(buf, 4)?;
        let n = BigEndian::read_i32(&buf[0..4]);
        if n < 0 || n as usize > MAX_BUTTONS {
            return Err(WireError::BadValue("button States count"));
        }
        let n = n as usize;
        need(buf, 4 + 4 * n)?;
        let mut s = States {
            count: n,
            ..States::default()
        };
        BigEndian::read_i32_into(&buf[4..4 + 4 * n], &mut s.states[..n]);
        Ok(s)
    }

    /// Writes the payload at the start of `out` (at least [`States::encoded_len`] bytes).
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let states = self.as_slice();
        let len = 4 + 4 * states.len();
        BigEndian::write_i32(&mut out[0..4], states.len() as i32);
        BigEndian::write_i32_into(states, &mut out[4..len]);
        len
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn round_trips() {
        let b = round_trip!(
            Change,
            Change {
                button: 1,
                state: ON
            }
        );
        assert_eq!(b, hex("0000000100000001"));
        round_trip!(
            Admin,
            Admin {
                button: ALL_ID,
                mode: TOGGLE_ON
            }
        );
        round_trip!(
            Alert,
            Alert {
                button: 3,
                event: TOGGLE_OFF
            }
        );
        assert!(Change::decode(&[0u8; 9]).is_err());
        assert!(Admin::decode(&[0u8; 9]).is_ok());

        for n in [0usize, 1, 7, MAX_BUTTONS] {
            let states: Vec<i32> = (0..n).map(|i| (i % 2) as i32).collect();
            let s = States::from_slice(&states);
            let mut buf = [0u8; 4 + 4 * MAX_BUTTONS];
            let len = s.encode(&mut buf);
            assert_eq!(len, s.encoded_len());
            assert_eq!(len, 4 + 4 * n);
            let back = States::decode(&buf[..len]).unwrap();
            assert_eq!(back, s);
            assert_eq!(back.as_slice(), &states[..]);
            for cut in 0..len {
                assert!(States::decode(&buf[..cut]).is_err());
            }
        }
    }

    #[test]
    fn states_refuses_bad_counts() {
        assert!(States::decode(&hex("ffffffff")).is_err());
        let mut big = vec![0u8; 4 + 4 * 300];
        big[2] = 1; // n = 256 + 44 = 300
        big[3] = 44;
        assert!(States::decode(&big).is_err());
    }

    #[test]
    fn golden_button_messages() {
        // button_analog_dial: vrpn_Button_Example_Server with two buttons.
        let s = States::decode(&hex("000000020000000100000001")).unwrap();
        assert_eq!(s.as_slice(), &[1, 1]);
        let mut out = [0u8; 12];
        assert_eq!(s.encode(&mut out), 12);
        assert_eq!(out.to_vec(), hex("000000020000000100000001"));
        let c = Change::decode(&hex("0000000000000000")).unwrap();
        assert_eq!(
            c,
            Change {
                button: 0,
                state: 0
            }
        );
    }
}
