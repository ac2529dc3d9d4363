//! The reports a 5DT USB glove sends, byte for byte.

/// A 64-byte report: sixteen big-endian `i16` sensor values (4096 = fully bent), the rest 0.
pub fn report(values: [i16; 16]) -> Vec<u8> {
    let mut r = vec![0u8; 64];
    for (i, v) in values.iter().enumerate() {
        r[2 * i..2 * i + 2].copy_from_slice(&v.to_be_bytes());
    }
    r
}

/// A few reports: a hand opening and closing.
pub fn samples() -> Vec<Vec<u8>> {
    let mut ramp = [0i16; 16];
    for (i, v) in ramp.iter_mut().enumerate() {
        *v = (i as i16) * 300 - 1000;
    }
    vec![report(ramp), report([4096; 16]), report([0; 16])]
}
