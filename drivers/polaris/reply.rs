//! NDI replies: lines of ASCII ending in CR whose last four characters are a CRC-16 of the rest
//! (upper-case hex), found byte by byte ([`ReplyReader`]), and the `TX` reply's poses
//! ([`parse_tx`]). Pure: bytes and times in, replies out.
//!
//! A reply whose CRC does not match is not given up at once: garbage that came before a
//! reply (with no CR of its own) ends up at the front of the reply's line, so the line's
//! suffixes are tried, and the longest one whose CRC matches is the reply, stamped with the
//! arrival of its own first byte.

use crate::time::Now;

/// The longest reply kept (a `TX` reply for 20 tools is under 1500 characters); a longer
/// line is garbage.
pub const MAX_REPLY: usize = 2048;
/// The most tools (port handles) a `TX` reply may carry here (C++ takes at most 20 tools).
pub const MAX_HANDLES: usize = 20;

/// CRC-16 of NDI replies (polynomial 0x8005 reflected, initial value 0: `OKAY` → `A896`).
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    for &b in bytes {
        crc ^= u16::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xA001
            } else {
                crc >> 1
            };
        }
    }
    crc
}

/// Appends `body`, its CRC and CR: a reply as the tracker sends it (for the simulator and
/// tests).
pub fn with_crc(body: &[u8], out: &mut Vec<u8>) {
    use std::io::Write;
    out.extend_from_slice(body);
    let _ = write!(out, "{:04X}\r", crc16(body));
}

fn hex_digit(b: u8) -> Option<u32> {
    (b as char).to_digit(16)
}

/// The value of `bytes` as hex digits, if they all are.
pub fn hex(bytes: &[u8]) -> Option<u32> {
    bytes
        .iter()
        .try_fold(0u32, |v, &b| Some(v.checked_mul(16)? + hex_digit(b)?))
}

/// True when `line` ends in a CRC of what comes before it.
fn crc_ok(line: &[u8]) -> bool {
    let Some(split) = line.len().checked_sub(4) else {
        return false;
    };
    let (body, tail) = line.split_at(split);
    tail.iter().all(|b| !b.is_ascii_lowercase())
        && hex(tail).is_some_and(|c| c == u32::from(crc16(body)))
}

/// A reply found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reply<'a> {
    /// The reply without its CRC and CR.
    pub body: &'a [u8],
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes dropped before it (garbage, damaged replies) since the previous reply.
    pub skipped: usize,
}

/// Finds replies byte by byte. See the module documentation.
pub struct ReplyReader {
    buf: Box<[u8; MAX_REPLY]>,
    times: Box<[Option<Now>; MAX_REPLY]>,
    len: usize,
    skipped: usize,
    overflowed: bool,
}

impl Default for ReplyReader {
    fn default() -> ReplyReader {
        ReplyReader::new()
    }
}

impl ReplyReader {
    /// An empty reader.
    pub fn new() -> ReplyReader {
        ReplyReader {
            buf: Box::new([0; MAX_REPLY]),
            times: Box::new([None; MAX_REPLY]),
            len: 0,
            skipped: 0,
            overflowed: false,
        }
    }

    /// Forgets a partial reply.
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
        self.overflowed = false;
    }

    /// Takes one byte that arrived at `arrived`; returns a reply when this byte (a CR)
    /// completes one whose CRC matches. A line that holds none is counted as skipped.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Reply<'_>> {
        if b != b'\r' {
            if self.len == MAX_REPLY {
                // Too long to be a reply: drop what we have.
                self.skipped += self.len;
                self.len = 0;
                self.overflowed = true;
            }
            self.buf[self.len] = b;
            self.times[self.len] = Some(arrived);
            self.len += 1;
            return None;
        }
        let len = std::mem::take(&mut self.len);
        let overflowed = std::mem::take(&mut self.overflowed);
        let line = &self.buf[..len];
        let start = if overflowed {
            None
        } else {
            (0..len.saturating_sub(4)).find(|&s| crc_ok(&line[s..]))
        };
        match start {
            Some(s) => Some(Reply {
                body: &self.buf[s..len - 4],
                first_byte: self.times[s].unwrap_or(arrived),
                skipped: std::mem::take(&mut self.skipped) + s,
            }),
            None => {
                self.skipped += len + 1;
                None
            }
        }
    }

    /// Bytes dropped since the last reply.
    pub fn pending_skipped(&self) -> usize {
        self.skipped
    }
}

/// One tool's entry in a `TX` reply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolPose {
    /// Its port handle.
    pub handle: u8,
    /// Position, millimetres.
    pub pos: [f64; 3],
    /// Quaternion x, y, z, w.
    pub quat: [f64; 4],
    /// The tracker's frame number, where the reply has it.
    pub frame: Option<u32>,
}

/// What a `TX` reply says of one port handle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ToolState {
    /// Seen: its pose.
    Seen(ToolPose),
    /// Not seen (`MISSING`) or not enabled (`DISABLED`).
    Unseen(u8),
}

/// Why a reply is not a `TX` reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TxError {
    /// Shorter than its handles need, or a field not in its format (the offset).
    Malformed(usize),
    /// More handles than [`MAX_HANDLES`].
    TooManyHandles(u32),
}

fn signed(field: &[u8], scale: f64) -> Option<f64> {
    let (sign, digits) = field.split_first()?;
    let sign = match sign {
        b'+' => 1.0,
        b'-' => -1.0,
        _ => return None,
    };
    let v = digits
        .iter()
        .try_fold(0u32, |v, &b| Some(v * 10 + (b as char).to_digit(10)?))?;
    Some(sign * f64::from(v) / scale)
}

/// Parses a `TX` reply (reply option 0001, the default): the handle count (2 hex), then per
/// handle its number (2 hex) and either `MISSING`/`DISABLED` or q0 qx qy qz (sign and 5
/// digits, ×10⁻⁴), tx ty tz (sign and 6 digits, ×10⁻² mm), the fit error, the port status
/// and the frame number (8 hex), each handle's entry ending in LF; then the system status.
/// Calls `each` for every handle, in order.
pub fn parse_tx(body: &[u8], mut each: impl FnMut(ToolState)) -> Result<(), TxError> {
    let count = body.get(..2).and_then(hex).ok_or(TxError::Malformed(0))?;
    if count as usize > MAX_HANDLES {
        return Err(TxError::TooManyHandles(count));
    }
    // Check the whole reply before reporting any of it.
    for pass in 0..2 {
        let mut at = 2;
        for _ in 0..count {
            let line_end = body[at..]
                .iter()
                .position(|&b| b == b'\n')
                .map(|p| at + p)
                .ok_or(TxError::Malformed(at))?;
            let entry = &body[at..line_end];
            let state = tool(entry).ok_or(TxError::Malformed(at))?;
            if pass == 1 {
                each(state);
            }
            at = line_end + 1;
        }
        if body.len() - at != 4 || hex(&body[at..]).is_none() {
            return Err(TxError::Malformed(at));
        }
    }
    Ok(())
}

/// One handle's entry, without its LF.
fn tool(entry: &[u8]) -> Option<ToolState> {
    let handle = u8::try_from(hex(entry.get(..2)?)?).ok()?;
    let rest = &entry[2..];
    if rest.starts_with(b"MISSING") || rest.starts_with(b"DISABLED") {
        return Some(ToolState::Unseen(handle));
    }
    let q = |i: usize| signed(rest.get(i * 6..i * 6 + 6)?, 10_000.0);
    let t = |i: usize| signed(rest.get(24 + i * 7..31 + i * 7)?, 100.0);
    let (w, x, y, z) = (q(0)?, q(1)?, q(2)?, q(3)?);
    let pos = [t(0)?, t(1)?, t(2)?];
    // Fit error (6), port status (8 hex), frame number (8 hex), when present.
    let frame = match rest.get(45..) {
        Some(tail) if tail.len() == 22 => Some(hex(&tail[14..])?),
        Some([]) | None => None,
        Some(_) => return None,
    };
    Some(ToolState::Seen(ToolPose {
        handle,
        pos,
        quat: [x, y, z, w],
        frame,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    #[test]
    fn the_crc_is_ndi_s() {
        assert_eq!(crc16(b"OKAY"), 0xA896);
        assert_eq!(crc16(b"RESET"), 0xBE6F);
        let mut v = Vec::new();
        with_crc(b"OKAY", &mut v);
        assert_eq!(v, b"OKAYA896\r");
    }

    #[test]
    fn replies_are_found_after_garbage_with_their_own_first_byte() {
        let base = Instant::now();
        let at = |ms: u64| Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(5, 0).plus(Duration::from_millis(ms)),
        };
        let mut r = ReplyReader::new();
        let mut got = Vec::new();
        let mut feed = |bytes: &[u8], ms: u64, got: &mut Vec<(Vec<u8>, Now, usize)>| {
            for &b in bytes {
                if let Some(rep) = r.push(b, at(ms)) {
                    got.push((rep.body.to_vec(), rep.first_byte, rep.skipped));
                }
            }
        };
        feed(b"xx\x01", 0, &mut got);
        feed(b"OKAYA896\r", 1, &mut got);
        feed(b"junk\r", 2, &mut got);
        feed(b"OKAYA897\r", 3, &mut got);
        feed(b"RESETBE6F\r", 4, &mut got);
        assert_eq!(
            got,
            [(b"OKAY".to_vec(), at(1), 3), (b"RESET".to_vec(), at(4), 14)]
        );
    }

    #[test]
    fn tx_replies_give_every_handle_in_order() {
        let body = b"02\
                     01+05000+00000-08660+00000+001234-000500+123456+00012000000310000002A\n\
                     02MISSING0000000000000000\n\
                     0000";
        let mut seen = Vec::new();
        parse_tx(body, |s| seen.push(s)).unwrap();
        assert_eq!(
            seen,
            [
                ToolState::Seen(ToolPose {
                    handle: 1,
                    pos: [12.34, -5.0, 1234.56],
                    quat: [0.0, -0.866, 0.0, 0.5],
                    frame: Some(0x2A),
                }),
                ToolState::Unseen(2),
            ]
        );
        assert!(parse_tx(b"01\n0000", |_| {}).is_err());
        assert!(parse_tx(b"0101+0500\n0000", |_| {}).is_err());
        assert!(parse_tx(b"00000", |_| {}).is_err());
        assert_eq!(parse_tx(b"000000", |_| {}), Ok(()));
    }
}
