//! Tracker messages: poses, velocities and accelerations per sensor, the
//! tracker-to-room and unit-to-sensor transforms, the workspace, and the client requests.
//!
//! Quaternions are `[x, y, z, w]`. The C++ remote checks every server->client length exactly
//! (a wrong length drops the connection), so those decoders use exact lengths. The request
//! types `Request_*` and `Reset_Origin` carry no payload and have no struct here.

/// Pose report, server->client, 64 bytes ([`PosQuat`]).
pub const POS_QUAT: &str = "vrpn_Tracker Pos_Quat";
/// Velocity report, server->client, 72 bytes ([`Velocity`]).
pub const VELOCITY: &str = "vrpn_Tracker Velocity";
/// Acceleration report, server->client, 72 bytes ([`Acceleration`]).
pub const ACCELERATION: &str = "vrpn_Tracker Acceleration";
/// Tracker-to-room transform reply, server->client, 56 bytes ([`ToRoom`]).
pub const TO_ROOM: &str = "vrpn_Tracker To_Room";
/// Unit-to-sensor transform reply, one per sensor, 64 bytes ([`UnitToSensor`]).
pub const UNIT_TO_SENSOR: &str = "vrpn_Tracker Unit_To_Sensor";
/// Client request for [`TO_ROOM`]; empty payload.
pub const REQUEST_TRACKER_TO_ROOM: &str = "vrpn_Tracker Request_Tracker_To_Room";
/// Client request for [`UNIT_TO_SENSOR`]; empty payload.
pub const REQUEST_UNIT_TO_SENSOR: &str = "vrpn_Tracker Request_Unit_To_Sensor";
/// Workspace reply, server->client, 48 bytes ([`Workspace`]).
pub const WORKSPACE: &str = "vrpn_Tracker Workspace";
/// Client request for [`WORKSPACE`]; empty payload.
pub const REQUEST_TRACKER_WORKSPACE: &str = "vrpn_Tracker Request_Tracker_Workspace";
/// Client request for a report rate, 8 bytes ([`UpdateRate`]).
pub const SET_UPDATE_RATE: &str = "vrpn_Tracker set_update_rate";
/// Client request to re-zero the tracker; empty payload.
pub const RESET_ORIGIN: &str = "vrpn_Tracker Reset_Origin";

/// Every tracker type name in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[
    POS_QUAT,
    VELOCITY,
    ACCELERATION,
    TO_ROOM,
    UNIT_TO_SENSOR,
    REQUEST_TRACKER_TO_ROOM,
    REQUEST_UNIT_TO_SENSOR,
    WORKSPACE,
    REQUEST_TRACKER_WORKSPACE,
    SET_UPDATE_RATE,
    RESET_ORIGIN,
];

/// The identity quaternion `[x, y, z, w]`.
pub const IDENTITY_QUAT: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

fixed_payload! {
    /// `vrpn_Tracker Pos_Quat`: one sensor's pose in the tracker frame.
    ///
    /// Decoding is exact-length (64). C++ also refuses a negative sensor; that check belongs to
    /// the caller. Use [`PosQuat::new`] to get the C++ filler (a copy of the sensor index).
    pub struct PosQuat: exact {
        /// Sensor index, 0-based.
        pub sensor: i32,
        /// Alignment filler as on the wire; C++ servers write the sensor index again.
        pub pad: i32,
        /// Position in metres, `[x, y, z]`.
        pub pos: [f64; 3],
        /// Orientation `[x, y, z, w]`.
        pub quat: [f64; 4],
    }
}

impl PosQuat {
    /// A report as a C++ server builds it (filler = sensor index).
    pub fn new(sensor: i32, pos: [f64; 3], quat: [f64; 4]) -> PosQuat {
        PosQuat {
            sensor,
            pad: sensor,
            pos,
            quat,
        }
    }
}

fixed_payload! {
    /// `vrpn_Tracker Velocity`: one sensor's linear velocity and rotation rate.
    ///
    /// Decoding is exact-length (72). [`Velocity::new`] sets the C++ filler.
    pub struct Velocity: exact {
        /// Sensor index, 0-based.
        pub sensor: i32,
        /// Alignment filler as on the wire; C++ servers write the sensor index again.
        pub pad: i32,
        /// Linear velocity in m/s.
        pub vel: [f64; 3],
        /// Rotation the sensor undergoes during `vel_quat_dt` seconds, `[x, y, z, w]`.
        pub vel_quat: [f64; 4],
        /// Interval of `vel_quat`, in seconds.
        pub vel_quat_dt: f64,
    }
}

impl Velocity {
    /// A report as a C++ server builds it (filler = sensor index).
    pub fn new(sensor: i32, vel: [f64; 3], vel_quat: [f64; 4], vel_quat_dt: f64) -> Velocity {
        Velocity {
            sensor,
            pad: sensor,
            vel,
            vel_quat,
            vel_quat_dt,
        }
    }
}

fixed_payload! {
    /// `vrpn_Tracker Acceleration`: one sensor's linear and angular acceleration.
    ///
    /// Decoding is exact-length (72). [`Acceleration::new`] sets the C++ filler.
    pub struct Acceleration: exact {
        /// Sensor index, 0-based.
        pub sensor: i32,
        /// Alignment filler as on the wire; C++ servers write the sensor index again.
        pub pad: i32,
        /// Linear acceleration in m/s².
        pub acc: [f64; 3],
        /// Change of the velocity quaternion over `acc_quat_dt`, `[x, y, z, w]`.
        pub acc_quat: [f64; 4],
        /// Interval of `acc_quat`, in seconds.
        pub acc_quat_dt: f64,
    }
}

impl Acceleration {
    /// A report as a C++ server builds it (filler = sensor index).
    pub fn new(sensor: i32, acc: [f64; 3], acc_quat: [f64; 4], acc_quat_dt: f64) -> Acceleration {
        Acceleration {
            sensor,
            pad: sensor,
            acc,
            acc_quat,
            acc_quat_dt,
        }
    }
}

fixed_payload! {
    /// `vrpn_Tracker To_Room`: the tracker-to-room transform. Exact length 56.
    pub struct ToRoom: exact {
        /// Translation `[x, y, z]`.
        pub pos: [f64; 3],
        /// Rotation `[x, y, z, w]`.
        pub quat: [f64; 4],
    }
}

fixed_payload! {
    /// `vrpn_Tracker Unit_To_Sensor`: one sensor's unit-to-sensor transform. Exact length 64.
    ///
    /// Unlike the reports, C++ writes 0 into the filler here; [`UnitToSensor::new`] does too.
    pub struct UnitToSensor: exact {
        /// Sensor index, 0-based.
        pub sensor: i32,
        /// Alignment filler as on the wire (0 from C++).
        pub pad: i32,
        /// Translation `[x, y, z]`.
        pub pos: [f64; 3],
        /// Rotation `[x, y, z, w]`.
        pub quat: [f64; 4],
    }
}

impl UnitToSensor {
    /// A reply as a C++ server builds it (filler = 0).
    pub fn new(sensor: i32, pos: [f64; 3], quat: [f64; 4]) -> UnitToSensor {
        UnitToSensor {
            sensor,
            pad: 0,
            pos,
            quat,
        }
    }
}

fixed_payload! {
    /// `vrpn_Tracker Workspace`: the axis-aligned working volume. Exact length 48.
    pub struct Workspace: exact {
        /// Minimum corner `[x, y, z]` in the tracker frame.
        pub min: [f64; 3],
        /// Maximum corner `[x, y, z]` in the tracker frame.
        pub max: [f64; 3],
    }
}

fixed_payload! {
    /// `vrpn_Tracker set_update_rate`: requested reports per second. Exact length 8 (the
    /// Phantom, the one C++ server that reads it, refuses any other length).
    pub struct UpdateRate: exact {
        /// Requested samples per second.
        pub rate: f64,
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;
    use crate::wire::WireError;

    #[test]
    fn lengths_match_devices_md() {
        assert_eq!(PosQuat::LEN, 64);
        assert_eq!(Velocity::LEN, 72);
        assert_eq!(Acceleration::LEN, 72);
        assert_eq!(ToRoom::LEN, 56);
        assert_eq!(UnitToSensor::LEN, 64);
        assert_eq!(Workspace::LEN, 48);
        assert_eq!(UpdateRate::LEN, 8);
    }

    #[test]
    fn round_trips() {
        let b = round_trip!(
            PosQuat,
            PosQuat::new(3, [1.0, -2.5, 3.25], [0.5, 0.5, 0.5, 0.5])
        );
        assert_eq!(&b[..8], &[0, 0, 0, 3, 0, 0, 0, 3]);
        round_trip!(
            Velocity,
            Velocity::new(1, [0.1, 0.2, 0.3], [0.0, 0.0, 0.0, 1.0], 0.9)
        );
        round_trip!(
            Acceleration,
            Acceleration::new(2, [9.81, 0.0, -1.0], IDENTITY_QUAT, 1.0)
        );
        round_trip!(
            ToRoom,
            ToRoom {
                pos: [1.0, 2.0, 3.0],
                quat: IDENTITY_QUAT
            }
        );
        let b = round_trip!(
            UnitToSensor,
            UnitToSensor::new(7, [0.0; 3], [0.0, 1.0, 0.0, 0.0])
        );
        assert_eq!(&b[..8], &[0, 0, 0, 7, 0, 0, 0, 0]);
        round_trip!(
            Workspace,
            Workspace {
                min: [-0.5; 3],
                max: [0.5; 3]
            }
        );
        round_trip!(UpdateRate, UpdateRate { rate: 60.0 });
    }

    #[test]
    fn exact_lengths_refuse_longer_payloads() {
        let buf = [0u8; 80];
        assert_eq!(
            PosQuat::decode(&buf[..65]),
            Err(WireError::BadValue("PosQuat payload length"))
        );
        assert!(Velocity::decode(&buf[..73]).is_err());
        assert!(PosQuat::decode(&buf[..63]).is_err());
    }

    #[test]
    fn golden_spin_pose_and_velocity() {
        // tracker_spin: UDP datagram from vrpn_Tracker_Spin (sensor 0).
        let p = hex(
            "00000000000000000000000000000000000000000000000000000000000000000000000000000000\
                     3fed6b350828d48400000000000000003fd92ea31f220275",
        );
        let pq = PosQuat::decode(&p).unwrap();
        assert_eq!(pq.sensor, 0);
        assert_eq!(pq.pad, 0);
        assert_eq!(pq.pos, [0.0; 3]);
        assert_eq!(pq.quat, [0.0, 0.9193368110051243, 0.0, 0.39347150841061956]);
        let mut out = [0u8; 64];
        pq.encode(&mut out);
        assert_eq!(&out[..], &p[..]);

        let v = hex(
            "00000000000000000000000000000000000000000000000000000000000000000000000000000000\
                     3fef9b24942fe45c00000000000000003fc4060b67a853773feccccccccccccd",
        );
        let vel = Velocity::decode(&v).unwrap();
        assert_eq!(
            vel.vel_quat,
            [0.0, 0.9876883405951378, 0.0, 0.15643446504023092]
        );
        assert_eq!(vel.vel_quat_dt, 0.9);
    }

    #[test]
    fn golden_pad_word_repeats_sensor() {
        // tracker_udp_lob: vrpn_Tracker_NULL sensor 1, Pos_Quat and Acceleration.
        let p = hex("00000001000000010000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000003ff0000000000000");
        let pq = PosQuat::decode(&p).unwrap();
        assert_eq!(pq, PosQuat::new(1, [0.0; 3], IDENTITY_QUAT));
        let a = hex("00000001000000010000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000003ff00000000000003ff0000000000000");
        let acc = Acceleration::decode(&a).unwrap();
        assert_eq!(acc, Acceleration::new(1, [0.0; 3], IDENTITY_QUAT, 1.0));
        let mut out = [0u8; 72];
        acc.encode(&mut out);
        assert_eq!(&out[..], &a[..]);
    }
}
