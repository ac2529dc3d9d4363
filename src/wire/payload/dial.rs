//! Dial messages: incremental rotation of one dial, in revolutions.

/// One dial's rotation since its last report, server->client, 12 bytes ([`Update`]).
pub const UPDATE: &str = "vrpn_Dial update";

/// Every dial type name in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[UPDATE];

/// Most dials per device.
pub const MAX_DIALS: usize = 128;

fixed_payload! {
    /// `vrpn_Dial update`: f64 change, then i32 dial (12 bytes, not padded to 16 in the
    /// payload). The C++ remote checks no length (≥ 12 here).
    pub struct Update: at_least {
        /// Revolutions since the previous report; the sign gives the direction.
        pub change: f64,
        /// Dial index, 0-based.
        pub dial: i32,
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn round_trips() {
        let b = round_trip!(
            Update,
            Update {
                change: -0.25,
                dial: 5
            }
        );
        assert_eq!(b, hex("bfd0000000000000 00000005"));
        assert_eq!(Update::LEN, 12);
    }

    #[test]
    fn golden_dial_example() {
        // button_analog_dial: vrpn_Dial_Example_Server, 1.0 rev/s at 10 reports/s.
        let p = hex("3fb999999999999a00000000");
        let u = Update::decode(&p).unwrap();
        assert_eq!(
            u,
            Update {
                change: 0.1,
                dial: 0
            }
        );
        let mut out = [0u8; 12];
        u.encode(&mut out);
        assert_eq!(out.to_vec(), p);
    }
}
