//! The inertial reports of the Oculus DK1 and DK2, the Laputa and the Vality vGlass, decoded
//! as C++ does, and the Oculus keep-alive feature reports.

use crate::drivers::hid_pad::{le_i16, le_u16, Skip};

/// A 21-bit two's-complement value.
fn sign21(v: i32) -> i32 {
    (v << 11) >> 11
}

/// Three 21-bit signed values packed big-endian into 8 bytes (accelerometer or gyroscope),
/// as C++'s `unpackVector` assembles them.
pub fn unpack_vector(raw: &[u8]) -> [i32; 3] {
    let b = |i: usize| i32::from(raw[i]);
    let x = (b(0) << 16) | (b(1) << 8) | b(2);
    let y = ((b(2) << 24) | (b(3) << 16) | (b(4) << 8) | b(5)) >> 6;
    let z = ((b(2) << 24) | (b(5) << 16) | (b(6) << 8) | b(7)) >> 1;
    [
        sign21((x >> 3) & 0x1f_ffff),
        sign21(y & 0x1f_ffff),
        sign21(z & 0x1f_ffff),
    ]
}

/// The inverse, for simulators: packs three 21-bit values.
pub fn pack_vector(v: [i32; 3]) -> [u8; 8] {
    let (x, y, z) = (
        (v[0] & 0x1f_ffff) as u64,
        (v[1] & 0x1f_ffff) as u64,
        (v[2] & 0x1f_ffff) as u64,
    );
    let bits: u64 = (x << 43) | (y << 22) | (z << 1);
    bits.to_be_bytes()
}

/// One inertial sample's channels: what is reported after each.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Imu {
    /// The channels (11 or 12 used).
    pub channel: [f64; 12],
}

impl Imu {
    fn sample(&mut self, accel: [i32; 3], gyro: [i32; 3]) {
        for k in 0..3 {
            self.channel[2 + k] = f64::from(accel[k]) * 0.0001;
            self.channel[5 + k] = f64::from(gyro[k]) * 0.0001;
        }
    }
}

/// Report type 1 of the Oculus DK1 and DK2 and of the Laputa (62 or 64 bytes): calls
/// `sample` after each of its (up to 3) inertial samples.
pub fn type_1(r: &[u8], imu: &mut Imu, mut sample: impl FnMut(&Imu)) -> Result<(), Skip> {
    check_len(r)?;
    let count = usize::from(r[1]).min(3);
    imu.channel[1] = f64::from(le_u16(r, 2));
    imu.channel[0] = f64::from(le_u16(r, 6)) * 0.01;
    for k in 0..3 {
        imu.channel[8 + k] = f64::from(-i32::from(le_i16(r, 56 + 2 * k))) * 0.0001;
    }
    for i in 0..count {
        let at = 8 + 16 * i;
        imu.sample(unpack_vector(&r[at..]), unpack_vector(&r[at + 8..]));
        sample(imu);
    }
    Ok(())
}

/// Report type 11 of the Oculus DK2 (62 or 64 bytes): up to 2 samples, each with its own
/// magnetometer reading, and the device's clock on channel 11.
pub fn type_11(r: &[u8], imu: &mut Imu, mut sample: impl FnMut(&Imu)) -> Result<(), Skip> {
    check_len(r)?;
    let count = usize::from(r[3]).min(2);
    imu.channel[1] = f64::from(le_u16(r, 4));
    imu.channel[0] = f64::from(le_u16(r, 6)) * 0.01;
    let us = u32::from_le_bytes([r[8], r[9], r[10], r[11]]);
    imu.channel[11] = f64::from(us) * 1e-6;
    for i in 0..count {
        let at = 12 + 16 * i;
        imu.sample(unpack_vector(&r[at..]), unpack_vector(&r[at + 8..]));
        for k in 0..3 {
            // C++ negates the value and multiplies by a negative scale.
            imu.channel[8 + k] = f64::from(-i32::from(le_i16(r, 44 + 8 * i + 2 * k))) * -0.0001;
        }
        sample(imu);
    }
    Ok(())
}

fn check_len(r: &[u8]) -> Result<(), Skip> {
    if r.len() == 62 || r.len() == 64 {
        Ok(())
    } else {
        Err(Skip::Length(r.len()))
    }
}

/// The Vality vGlass's report 1 (at least 24 bytes): accelerometer (m/s², negated) on
/// channels 0-2, gyroscope (rad/s) on 3-5.
pub fn vality(r: &[u8], imu: &mut Imu) -> Result<(), Skip> {
    if r.len() < 24 {
        return Err(Skip::Length(r.len()));
    }
    if r[0] != 1 {
        return Err(Skip::Kind(r[0]));
    }
    let mss = (1.0 / 32767.0) * 16.0 * 9.807;
    let rs = (1.0 / 32767.0) * 2000.0 * (std::f64::consts::PI / 180.0);
    for k in 0..3 {
        imu.channel[k] = f64::from(-i32::from(le_i16(r, 12 + 2 * k))) * mss;
        imu.channel[3 + k] = f64::from(le_i16(r, 6 + 2 * k)) * rs;
    }
    Ok(())
}

/// The keep-alive period C++ uses.
pub const KEEP_ALIVE_PERIOD: std::time::Duration = std::time::Duration::from_secs(9);
/// The keep-alive interval asked of the device, ms.
pub const KEEP_ALIVE_MS: u16 = 10_000;

/// The DK1's keep-alive feature report: `08`, command id 0, interval (ms), little-endian.
pub fn dk1_keep_alive() -> [u8; 5] {
    let i = KEEP_ALIVE_MS.to_le_bytes();
    [0x08, 0, 0, i[0], i[1]]
}

/// The DK2's keep-alive and LED-control feature report: `11`, command id 0, flags (0x0b
/// with the LEDs on, 0x01 inertial only), interval (ms).
pub fn dk2_keep_alive(leds: bool) -> [u8; 6] {
    let i = KEEP_ALIVE_MS.to_le_bytes();
    [0x11, 0, 0, if leds { 0x0b } else { 0x01 }, i[0], i[1]]
}
