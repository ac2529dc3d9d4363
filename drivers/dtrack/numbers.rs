//! Numbers read as the C library reads them (`strtol` base 0, `strtoul` base 10, `strtod`):
//! the controller's text is parsed the way C++ VRPN parses it, so the same datagram gives the
//! same values. Each function takes the text from the current position and returns the value
//! and the number of bytes it used, or `None` where C would return its argument unchanged.

/// C `isspace` in the "C" locale.
pub(super) fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | b'\x0b' | b'\x0c' | b'\r')
}

fn skip_space(s: &[u8]) -> usize {
    s.iter().take_while(|&&b| is_space(b)).count()
}

fn sign(s: &[u8], at: usize) -> (bool, usize) {
    match s.get(at) {
        Some(b'-') => (true, at + 1),
        Some(b'+') => (false, at + 1),
        _ => (false, at),
    }
}

fn digit(b: u8, radix: u32) -> Option<u32> {
    (b as char).to_digit(radix)
}

/// Digits from `at` in `radix`, saturating at `limit`: (value, end, any digit).
fn digits(s: &[u8], at: usize, radix: u32, limit: u64) -> (u64, usize) {
    let mut v: u64 = 0;
    let mut i = at;
    while let Some(d) = s.get(i).and_then(|&b| digit(b, radix)) {
        v = v
            .saturating_mul(radix as u64)
            .saturating_add(d as u64)
            .min(limit);
        i += 1;
    }
    (v, i)
}

/// `(int) strtol(s, &end, 0)`: decimal, `0x` hexadecimal or `0` octal, saturated to a C
/// `long` (64 bits) and then cut to 32 bits as the cast does.
pub(super) fn strtol_int(s: &[u8]) -> Option<(i32, usize)> {
    let start = skip_space(s);
    let (neg, at) = sign(s, start);
    let hex = s.get(at) == Some(&b'0')
        && matches!(s.get(at + 1), Some(b'x' | b'X'))
        && s.get(at + 2).and_then(|&b| digit(b, 16)).is_some();
    let (radix, from) = if hex {
        (16, at + 2)
    } else if s.get(at) == Some(&b'0') {
        (8, at)
    } else {
        (10, at)
    };
    let limit = if neg {
        i64::MAX as u64 + 1
    } else {
        i64::MAX as u64
    };
    let (v, end) = digits(s, from, radix, limit);
    if end == from {
        return None;
    }
    let long = if neg {
        (v as i64).wrapping_neg()
    } else {
        v as i64
    };
    Some((long as i32, end))
}

/// `(unsigned int) strtoul(s, &end, 10)`: a minus sign negates modulo 2^64, as C does.
pub(super) fn strtoul_uint(s: &[u8]) -> Option<(u32, usize)> {
    let start = skip_space(s);
    let (neg, at) = sign(s, start);
    let (v, end) = digits(s, at, 10, u64::MAX);
    if end == at {
        return None;
    }
    let v = if neg { v.wrapping_neg() } else { v };
    Some((v as u32, end))
}

fn eq_ignore_case(s: &[u8], at: usize, word: &str) -> bool {
    s.get(at..at + word.len())
        .is_some_and(|w| w.eq_ignore_ascii_case(word.as_bytes()))
}

/// `strtod(s, &end)` for decimal numbers, `inf`, `infinity` and `nan`.
pub(super) fn strtod(s: &[u8]) -> Option<(f64, usize)> {
    let start = skip_space(s);
    let (neg, at) = sign(s, start);
    let signed = |v: f64| if neg { -v } else { v };
    if eq_ignore_case(s, at, "infinity") {
        return Some((signed(f64::INFINITY), at + 8));
    }
    if eq_ignore_case(s, at, "inf") {
        return Some((signed(f64::INFINITY), at + 3));
    }
    if eq_ignore_case(s, at, "nan") {
        let mut end = at + 3;
        // nan(chars): the parenthesised part is consumed when closed.
        if s.get(end) == Some(&b'(') {
            let close = s[end..]
                .iter()
                .position(|&b| !(b.is_ascii_alphanumeric() || b == b'_' || b == b'('));
            if let Some(p) = close.filter(|&p| s[end + p] == b')') {
                end += p + 1;
            }
        }
        return Some((signed(f64::NAN), end));
    }
    let mut i = at;
    let int_digits = s[i..].iter().take_while(|b| b.is_ascii_digit()).count();
    i += int_digits;
    let mut frac_digits = 0;
    if s.get(i) == Some(&b'.') {
        frac_digits = s[i + 1..].iter().take_while(|b| b.is_ascii_digit()).count();
        if int_digits + frac_digits > 0 {
            i += 1 + frac_digits;
        }
    }
    if int_digits + frac_digits == 0 {
        return None;
    }
    if matches!(s.get(i), Some(b'e' | b'E')) {
        let (_, e) = sign(s, i + 1);
        let exp_digits = s[e.min(s.len())..]
            .iter()
            .take_while(|b| b.is_ascii_digit())
            .count();
        if exp_digits > 0 {
            i = e + exp_digits;
        }
    }
    let text = std::str::from_utf8(&s[at..i]).ok()?;
    let v: f64 = text.parse().ok()?;
    Some((signed(v), i))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strtol_like_c() {
        assert_eq!(strtol_int(b"  42 x"), Some((42, 4)));
        assert_eq!(strtol_int(b"-7]"), Some((-7, 2)));
        assert_eq!(strtol_int(b"0x1F"), Some((31, 4)));
        assert_eq!(strtol_int(b"010"), Some((8, 3)));
        assert_eq!(strtol_int(b"08"), Some((0, 1)));
        assert_eq!(strtol_int(b"0x"), Some((0, 1)));
        assert_eq!(strtol_int(b"\n5"), Some((5, 2)));
        assert_eq!(strtol_int(b"x"), None);
        assert_eq!(strtol_int(b"-"), None);
        assert_eq!(strtol_int(b""), None);
        // Saturated to LONG_MAX, then cut to int: -1.
        assert_eq!(strtol_int(b"99999999999999999999"), Some((-1, 20)));
        assert_eq!(strtol_int(b"4294967297"), Some((1, 10)));
    }

    #[test]
    fn strtoul_like_c() {
        assert_eq!(strtoul_uint(b" 123 "), Some((123, 4)));
        assert_eq!(strtoul_uint(b"-1"), Some((u32::MAX, 2)));
        assert_eq!(strtoul_uint(b"0x10"), Some((0, 1)));
        assert_eq!(strtoul_uint(b"abc"), None);
    }

    #[test]
    fn strtod_like_c() {
        assert_eq!(strtod(b"1.5 "), Some((1.5, 3)));
        assert_eq!(strtod(b" -0.25]"), Some((-0.25, 6)));
        assert_eq!(strtod(b"1e3"), Some((1000.0, 3)));
        assert_eq!(strtod(b"1e"), Some((1.0, 1)));
        assert_eq!(strtod(b"1.e-2x"), Some((0.01, 5)));
        assert_eq!(strtod(b".5"), Some((0.5, 2)));
        assert_eq!(strtod(b"."), None);
        assert_eq!(strtod(b"-"), None);
        assert_eq!(strtod(b"INF"), Some((f64::INFINITY, 3)));
        assert!(strtod(b"nan").unwrap().0.is_nan());
        assert_eq!(strtod(b"+2"), Some((2.0, 2)));
        assert_eq!(strtod(b"1e999"), Some((f64::INFINITY, 5)));
    }
}
