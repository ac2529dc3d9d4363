//! The reports X-keys devices send, byte for byte (one `read` each, as Linux's hidraw
//! delivers them: the original models split their 14-byte report into an 8-byte and a
//! 6-byte read).

/// A Desktop's 11-byte report: keys 0-19 five to a byte in bytes 0-3, byte 10 = 0x08 (always
/// set) | 0x10 when the programming switch is red.
pub fn desktop(switch: bool, keys: u32) -> Vec<u8> {
    let mut r = vec![0u8; 11];
    for k in 0..20 {
        if keys & (1 << k) != 0 {
            r[k / 5] |= 1 << (k % 5);
        }
    }
    r[10] = 0x08 | if switch { 0x10 } else { 0 };
    r
}

fn put7(r: &mut [u8], first_byte: usize, keys: u64, range: std::ops::Range<usize>) {
    for k in range.clone() {
        if keys & (1 << k) != 0 {
            let local = k - range.start;
            r[first_byte + local / 7] |= 1 << (local % 7);
        }
    }
}

/// An original model's report as two reads: 8 bytes (`head` — the joystick or shuttle/jog
/// bytes — then keys 0-34, seven to a byte) and 6 bytes (keys 35-57, then byte 5 = 0x08 |
/// 0x10 when the switch is red).
pub fn halves(head: [u8; 3], switch: bool, keys: u64) -> (Vec<u8>, Vec<u8>) {
    let mut a = vec![0u8; 8];
    a[..3].copy_from_slice(&head);
    put7(&mut a, 3, keys, 0..35);
    let mut b = vec![0u8; 6];
    put7(&mut b, 0, keys, 35..58);
    b[5] = 0x08 | if switch { 0x10 } else { 0 };
    (a, b)
}

/// An original model's report in one 14-byte read (how Windows delivers it): `head`, keys
/// 0-57 seven to a byte from byte 3, byte 13 = 0x08 | 0x10 when the switch is red.
pub fn whole(head: [u8; 3], switch: bool, keys: u64) -> Vec<u8> {
    let mut r = vec![0u8; 14];
    r[..3].copy_from_slice(&head);
    put7(&mut r, 3, keys, 0..58);
    r[13] |= 0x08 | if switch { 0x10 } else { 0 };
    r
}

/// A 12-key model's 32-byte report: byte 1 the switch, keys 0-11 three to a byte from byte
/// 2, then `tail` at bytes 6, 7, 8 (jog and shuttle, or joystick X, Y and twist).
pub fn twelve(switch: bool, keys: u32, tail: [u8; 3]) -> Vec<u8> {
    let mut r = vec![0u8; 32];
    r[1] = u8::from(switch);
    for k in 0..12 {
        if keys & (1 << k) != 0 {
            r[2 + k / 3] |= 1 << (k % 3);
        }
    }
    r[6..9].copy_from_slice(&tail);
    r
}

/// The slot of key `k` of a 68-key model (the middle four columns have five keys).
pub fn slot68(k: usize) -> usize {
    k + 3 * (usize::from(k > 28) + usize::from(k > 33) + usize::from(k > 38) + usize::from(k > 43))
}

/// A 68-key jog-and-shuttle's 32-byte report: keys in eight-slot columns from byte 2, jog at
/// byte 16, shuttle at 17.
pub fn sixty_eight(switch: bool, keys: u128, jog: i8, shuttle: i8) -> Vec<u8> {
    let mut r = vec![0u8; 32];
    r[1] = u8::from(switch);
    for k in 0..68 {
        if keys & (1 << k) != 0 {
            let s = slot68(k);
            r[2 + s / 8] |= 1 << (s % 8);
        }
    }
    r[16] = jog as u8;
    r[17] = shuttle as u8;
    r
}

/// The XK-3 foot switch's 32-byte report: `00 01`, then pedals as bits 1-3 of byte 2.
pub fn xk3(pedals: [bool; 3]) -> Vec<u8> {
    let mut r = vec![0u8; 32];
    r[1] = 1;
    for (i, p) in pedals.iter().enumerate() {
        if *p {
            r[2] |= 2 << i;
        }
    }
    r
}

/// A few reads exercising the keys, switch, shuttle, jog or joystick of `model`.
pub fn samples(model: &super::Model) -> Vec<Vec<u8>> {
    use super::Kind;
    match model.kind {
        Kind::Desktop => vec![desktop(true, 1 | 1 << 19), desktop(false, 1 << 7)],
        Kind::Pro | Kind::Joystick | Kind::JogAndShuttle => {
            let (a, b) = halves([0, 200, 60], true, 1 | 1 << 40);
            let (c, d) = halves([(-7i8) as u8, 30, 255], false, 1 << 57);
            vec![
                a,
                b,
                c,
                d,
                whole([64, 64, 10], true, 1 << 3),
                whole([64, 64, 14], true, 0),
            ]
        }
        Kind::Joystick12 => vec![
            twelve(true, 1 | 1 << 11, [127, 0x81, 100]),
            twelve(false, 1 << 5, [0, 10, 98]),
        ],
        Kind::JogAndShuttle12 => vec![
            twelve(true, 1, [2, (-3i8) as u8, 0]),
            twelve(false, 1 << 11, [(-1i8) as u8, 7, 0]),
        ],
        Kind::JogAndShuttle68 => vec![
            sixty_eight(false, 1 | 1 << 29 | 1 << 67, -2, 7),
            sixty_eight(true, 1 << 44, 3, -7),
        ],
        Kind::Xk3 => vec![xk3([true, false, true]), xk3([false, true, false])],
    }
}
