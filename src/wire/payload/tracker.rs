//! Tracker payloads (DEVICES.md §2).

use byteorder::{BigEndian, ByteOrder};

use crate::wire::{Result, WireError};

/// `vrpn_Tracker Pos_Quat`.
pub const POS_QUAT: &str = "vrpn_Tracker Pos_Quat";
/// `vrpn_Tracker Velocity`.
pub const VELOCITY: &str = "vrpn_Tracker Velocity";
/// `vrpn_Tracker Acceleration`.
pub const ACCELERATION: &str = "vrpn_Tracker Acceleration";
/// `vrpn_Tracker To_Room`.
pub const TO_ROOM: &str = "vrpn_Tracker To_Room";
/// `vrpn_Tracker Unit_To_Sensor`.
pub const UNIT_TO_SENSOR: &str = "vrpn_Tracker Unit_To_Sensor";
/// `vrpn_Tracker Request_Tracker_To_Room`.
pub const REQUEST_TO_ROOM: &str = "vrpn_Tracker Request_Tracker_To_Room";
/// `vrpn_Tracker Request_Unit_To_Sensor`.
pub const REQUEST_UNIT_TO_SENSOR: &str = "vrpn_Tracker Request_Unit_To_Sensor";
/// `vrpn_Tracker Workspace`.
pub const WORKSPACE: &str = "vrpn_Tracker Workspace";
/// `vrpn_Tracker Request_Tracker_Workspace`.
pub const REQUEST_WORKSPACE: &str = "vrpn_Tracker Request_Tracker_Workspace";
/// `vrpn_Tracker set_update_rate`.
pub const SET_UPDATE_RATE: &str = "vrpn_Tracker set_update_rate";
/// `vrpn_Tracker Reset_Origin`.
pub const RESET_ORIGIN: &str = "vrpn_Tracker Reset_Origin";

/// Tracker type names in C++ registration order.
pub const TYPE_NAMES: [&str; 11] = [
    POS_QUAT,
    VELOCITY,
    ACCELERATION,
    TO_ROOM,
    UNIT_TO_SENSOR,
    REQUEST_TO_ROOM,
    REQUEST_UNIT_TO_SENSOR,
    WORKSPACE,
    REQUEST_WORKSPACE,
    SET_UPDATE_RATE,
    RESET_ORIGIN,
];

fn exact(buf: &[u8], len: usize) -> Result<()> {
    if buf.len() != len {
        return Err(WireError::BadValue("tracker payload length"));
    }
    Ok(())
}

fn read_f64s<const N: usize>(buf: &[u8]) -> [f64; N] {
    let mut out = [0.0; N];
    for (i, v) in out.iter_mut().enumerate() {
        *v = BigEndian::read_f64(&buf[i * 8..i * 8 + 8]);
    }
    out
}

fn write_f64s(buf: &mut [u8], vals: &[f64]) {
    for (i, v) in vals.iter().enumerate() {
        BigEndian::write_f64(&mut buf[i * 8..i * 8 + 8], *v);
    }
}

/// A pose report: sensor, pad word, position, quaternion (x, y, z, w). 64 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PosQuat {
    /// Sensor index.
    pub sensor: i32,
    /// Alignment word; C++ servers repeat the sensor index here.
    pub pad_word: i32,
    /// Position.
    pub pos: [f64; 3],
    /// Orientation (x, y, z, w).
    pub quat: [f64; 4],
}

impl PosQuat {
    /// Payload length.
    pub const LEN: usize = 64;

    /// Decodes; the length must be exactly 64 (the C++ remote drops other lengths).
    pub fn decode(buf: &[u8]) -> Result<Self> {
        exact(buf, Self::LEN)?;
        let v: [f64; 7] = read_f64s(&buf[8..]);
        Ok(PosQuat {
            sensor: BigEndian::read_i32(&buf[0..4]),
            pad_word: BigEndian::read_i32(&buf[4..8]),
            pos: [v[0], v[1], v[2]],
            quat: [v[3], v[4], v[5], v[6]],
        })
    }

    /// Encodes into the first 64 bytes of `buf`.
    pub fn encode(&self, buf: &mut [u8]) -> usize {
        BigEndian::write_i32(&mut buf[0..4], self.sensor);
        BigEndian::write_i32(&mut buf[4..8], self.pad_word);
        write_f64s(&mut buf[8..32], &self.pos);
        write_f64s(&mut buf[32..64], &self.quat);
        Self::LEN
    }
}

macro_rules! rate_report {
    ($name:ident, $doc:literal, $lin:ident, $rot:ident, $dt:ident) => {
        #[doc = $doc]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name {
            /// Sensor index.
            pub sensor: i32,
            /// Alignment word; C++ servers repeat the sensor index here.
            pub pad_word: i32,
            /// Linear part.
            pub $lin: [f64; 3],
            /// Rotation over `dt` (x, y, z, w).
            pub $rot: [f64; 4],
            /// Seconds the rotation spans.
            pub $dt: f64,
        }

        impl $name {
            /// Payload length.
            pub const LEN: usize = 72;

            /// Decodes; the length must be exactly 72.
            pub fn decode(buf: &[u8]) -> Result<Self> {
                exact(buf, Self::LEN)?;
                let v: [f64; 8] = read_f64s(&buf[8..]);
                Ok($name {
                    sensor: BigEndian::read_i32(&buf[0..4]),
                    pad_word: BigEndian::read_i32(&buf[4..8]),
                    $lin: [v[0], v[1], v[2]],
                    $rot: [v[3], v[4], v[5], v[6]],
                    $dt: v[7],
                })
            }

            /// Encodes into the first 72 bytes of `buf`.
            pub fn encode(&self, buf: &mut [u8]) -> usize {
                BigEndian::write_i32(&mut buf[0..4], self.sensor);
                BigEndian::write_i32(&mut buf[4..8], self.pad_word);
                write_f64s(&mut buf[8..32], &self.$lin);
                write_f64s(&mut buf[32..64], &self.$rot);
                BigEndian::write_f64(&mut buf[64..72], self.$dt);
                Self::LEN
            }
        }
    };
}

rate_report!(
    Velocity,
    "A velocity report: sensor, pad, velocity, rotation over dt, dt. 72 bytes.",
    vel,
    vel_quat,
    vel_quat_dt
);
rate_report!(
    Acceleration,
    "An acceleration report: sensor, pad, acceleration, rotation change over dt, dt. 72 bytes.",
    acc,
    acc_quat,
    acc_quat_dt
);

/// Tracker-to-room transform: translation and rotation. 56 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToRoom {
    /// Translation.
    pub pos: [f64; 3],
    /// Rotation (x, y, z, w).
    pub quat: [f64; 4],
}

impl ToRoom {
    /// Payload length.
    pub const LEN: usize = 56;

    /// Decodes; the length must be exactly 56.
    pub fn decode(buf: &[u8]) -> Result<Self> {
        exact(buf, Self::LEN)?;
        let v: [f64; 7] = read_f64s(buf);
        Ok(ToRoom {
            pos: [v[0], v[1], v[2]],
            quat: [v[3], v[4], v[5], v[6]],
        })
    }

    /// Encodes into the first 56 bytes of `buf`.
    pub fn encode(&self, buf: &mut [u8]) -> usize {
        write_f64s(&mut buf[0..24], &self.pos);
        write_f64s(&mut buf[24..56], &self.quat);
        Self::LEN
    }
}

/// Unit-to-sensor transform of one sensor. 64 bytes; the pad word is 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitToSensor {
    /// Sensor index.
    pub sensor: i32,
    /// Alignment word (0 from C++).
    pub pad_word: i32,
    /// Translation.
    pub pos: [f64; 3],
    /// Rotation (x, y, z, w).
    pub quat: [f64; 4],
}

impl UnitToSensor {
    /// Payload length.
    pub const LEN: usize = 64;

    /// Decodes; the length must be exactly 64.
    pub fn decode(buf: &[u8]) -> Result<Self> {
        let p = PosQuat::decode(buf)?;
        Ok(UnitToSensor {
            sensor: p.sensor,
            pad_word: p.pad_word,
            pos: p.pos,
            quat: p.quat,
        })
    }

    /// Encodes into the first 64 bytes of `buf`.
    pub fn encode(&self, buf: &mut [u8]) -> usize {
        PosQuat {
            sensor: self.sensor,
            pad_word: self.pad_word,
            pos: self.pos,
            quat: self.quat,
        }
        .encode(buf)
    }
}

/// Workspace box. 48 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Workspace {
    /// Minimum corner.
    pub min: [f64; 3],
    /// Maximum corner.
    pub max: [f64; 3],
}

impl Workspace {
    /// Payload length.
    pub const LEN: usize = 48;

    /// Decodes; the length must be exactly 48.
    pub fn decode(buf: &[u8]) -> Result<Self> {
        exact(buf, Self::LEN)?;
        let v: [f64; 6] = read_f64s(buf);
        Ok(Workspace {
            min: [v[0], v[1], v[2]],
            max: [v[3], v[4], v[5]],
        })
    }

    /// Encodes into the first 48 bytes of `buf`.
    pub fn encode(&self, buf: &mut [u8]) -> usize {
        write_f64s(&mut buf[0..24], &self.min);
        write_f64s(&mut buf[24..48], &self.max);
        Self::LEN
    }
}
