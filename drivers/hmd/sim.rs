//! The reports the head-mounted displays send, byte for byte.

use super::imu::pack_vector;

/// One inertial sample: accelerometer and gyroscope (21-bit counts of 0.0001 units).
pub type Sample = ([i32; 3], [i32; 3]);

/// An Oculus DK1/DK2 or Laputa report type 1 (`len` 62 or 64): sample count, counter,
/// temperature (0.01 °C), up to three samples, magnetometer (0.0001 gauss, sign inverted on
/// the host).
pub fn type_1(
    counter: u16,
    temperature: u16,
    samples: &[Sample],
    mag: [i16; 3],
    len: usize,
) -> Vec<u8> {
    let mut r = vec![0u8; len];
    r[0] = 1;
    r[1] = samples.len() as u8;
    r[2..4].copy_from_slice(&counter.to_le_bytes());
    r[6..8].copy_from_slice(&temperature.to_le_bytes());
    for (i, (a, g)) in samples.iter().take(3).enumerate() {
        r[8 + 16 * i..16 + 16 * i].copy_from_slice(&pack_vector(*a));
        r[16 + 16 * i..24 + 16 * i].copy_from_slice(&pack_vector(*g));
    }
    for k in 0..3 {
        r[56 + 2 * k..58 + 2 * k].copy_from_slice(&mag[k].to_le_bytes());
    }
    r
}

/// A DK2 report type 11 (64 bytes): counter, temperature, the device clock (µs), up to two
/// samples each with its magnetometer reading.
pub fn type_11(
    counter: u16,
    temperature: u16,
    micros: u32,
    samples: &[(Sample, [i16; 3])],
) -> Vec<u8> {
    let mut r = vec![0u8; 64];
    r[0] = 11;
    r[3] = samples.len() as u8;
    r[4..6].copy_from_slice(&counter.to_le_bytes());
    r[6..8].copy_from_slice(&temperature.to_le_bytes());
    r[8..12].copy_from_slice(&micros.to_le_bytes());
    for (i, ((a, g), m)) in samples.iter().take(2).enumerate() {
        r[12 + 16 * i..20 + 16 * i].copy_from_slice(&pack_vector(*a));
        r[20 + 16 * i..28 + 16 * i].copy_from_slice(&pack_vector(*g));
        for k in 0..3 {
            r[44 + 8 * i + 2 * k..46 + 8 * i + 2 * k].copy_from_slice(&m[k].to_le_bytes());
        }
    }
    r
}

/// A Vality vGlass report 1 (32 bytes): gyroscope at 6, accelerometer at 12.
pub fn vality(gyro: [i16; 3], accel: [i16; 3]) -> Vec<u8> {
    let mut r = vec![0u8; 32];
    r[0] = 1;
    for k in 0..3 {
        r[6 + 2 * k..8 + 2 * k].copy_from_slice(&gyro[k].to_le_bytes());
        r[12 + 2 * k..14 + 2 * k].copy_from_slice(&accel[k].to_le_bytes());
    }
    r
}

/// An OSVR HDK report: version and flag bits, sequence, orientation (14 fractional bits),
/// angular velocity (9 fractional bits), `len` 16 or 32.
pub fn hdk(first: u8, seq: u8, quat: [i16; 4], ang_vel: [i16; 3], len: usize) -> Vec<u8> {
    let mut r = vec![0u8; len];
    r[0] = first;
    r[1] = seq;
    for k in 0..4 {
        r[2 + 2 * k..4 + 2 * k].copy_from_slice(&quat[k].to_le_bytes());
    }
    for k in 0..3 {
        r[10 + 2 * k..12 + 2 * k].copy_from_slice(&ang_vel[k].to_le_bytes());
    }
    r
}
