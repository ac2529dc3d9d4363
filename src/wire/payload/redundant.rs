//! Redundant transmission control (`vrpn_RedundantController` / `vrpn_RedundantRemote`): a
//! client tells a sender how many extra copies of each message to send over UDP and how
//! far apart, and switches redundancy on or off. The copies themselves are ordinary
//! messages of the sender's own types; a receiver drops a copy by its type and timestamp.

use crate::time::TimeVal;

/// The controller's sender name (every controller uses it).
pub const CONTROLLER: &str = "vrpn Redundant Transmission Controller";
/// Set the number of copies and their interval, 20 bytes ([`SetDefaults`]).
pub const SET: &str = "vrpn_Red_Xmit_Ctrl set";
/// Switch redundancy on or off, 2 bytes ([`Enable`]).
pub const ENABLE: &str = "vrpn_Red_Xmit_Ctrl enable";

/// The controller's type names in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[SET, ENABLE];

/// How many timestamps per message type a C++ receiver remembers (`VRPN_RR_LENGTH`).
pub const RECEIVER_MEMORY: usize = 8;

fixed_payload! {
    /// `set`: u32 copies, the interval as i32 seconds and i32 microseconds, then 8 filler
    /// bytes (C++ counts `sizeof(timeval)`, 16 on 64-bit hosts, for the 8 it writes).
    /// At least 20 bytes.
    pub struct SetDefaults: at_least {
        /// Extra copies of each message.
        pub retransmissions: u32,
        /// Seconds between copies.
        pub interval_sec: i32,
        /// Microseconds between copies.
        pub interval_usec: i32,
        /// Filler.
        pub pad: [u8; 8],
    }
}

impl SetDefaults {
    /// A request for `retransmissions` copies `interval` apart (zero filler).
    pub fn new(retransmissions: u32, interval: TimeVal) -> SetDefaults {
        SetDefaults {
            retransmissions,
            interval_sec: interval.sec as i32,
            interval_usec: interval.usec as i32,
            pad: [0; 8],
        }
    }

    /// The interval.
    pub fn interval(&self) -> TimeVal {
        TimeVal {
            sec: i64::from(self.interval_sec),
            usec: i64::from(self.interval_usec),
        }
    }
}

fixed_payload! {
    /// `enable`: a 16-bit boolean. At least 2 bytes.
    pub struct Enable: at_least {
        /// Non-zero: on.
        pub on: i16,
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn layouts() {
        let b = round_trip!(
            SetDefaults,
            SetDefaults::new(2, TimeVal { sec: 0, usec: 5000 })
        );
        assert_eq!(b, hex("00000002 00000000 00001388 0000000000000000"));
        let b = round_trip!(Enable, Enable { on: 1 });
        assert_eq!(b, hex("0001"));
    }
}
