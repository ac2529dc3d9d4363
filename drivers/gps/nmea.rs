//! NMEA 0183 sentences, found byte by byte ([`SentenceReader`]), checked by their checksum,
//! and the GGA fix read from them ([`parse_gga`]). Pure: bytes and times in, fixes out.
//!
//! A sentence starts with `$` and ends with LF (a CR before it is dropped); a `*` followed
//! by two hex digits is the XOR of the bytes between `$` and `*` (a sentence without one is
//! taken as it is, as C++ VRPN does). A `$` in the middle of a sentence starts a new one: a
//! sentence cut short by garbage loses only itself.

use crate::time::Now;

/// The longest sentence kept (NMEA's limit is 82 characters; some receivers send longer
/// proprietary ones, which are skipped whole).
pub const MAX_SENTENCE: usize = 120;
/// Metres per foot (an altitude in feet is converted; C++'s constant).
pub const METRES_PER_FOOT: f64 = 1.0 / 3.280839895013;

/// A sentence found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sentence<'a> {
    /// The text between `$` and `*` (or the end).
    pub body: &'a str,
    /// When the read holding its `$` arrived.
    pub first_byte: Now,
    /// Bytes dropped before it since the previous sentence.
    pub skipped: usize,
}

/// Why a line was not a sentence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejected {
    /// Its checksum did not match.
    Checksum,
    /// Longer than [`MAX_SENTENCE`].
    TooLong,
    /// Not ASCII text.
    NotText,
}

/// Finds sentences byte by byte. See the module documentation.
pub struct SentenceReader {
    buf: [u8; MAX_SENTENCE],
    len: usize,
    first: Option<Now>,
    in_sentence: bool,
    /// Bytes taken since the `$`, the `$` included.
    raw: usize,
    too_long: bool,
    skipped: usize,
    rejected: Option<Rejected>,
}

impl Default for SentenceReader {
    fn default() -> SentenceReader {
        SentenceReader::new()
    }
}

impl SentenceReader {
    /// An empty reader.
    pub fn new() -> SentenceReader {
        SentenceReader {
            buf: [0; MAX_SENTENCE],
            len: 0,
            first: None,
            in_sentence: false,
            raw: 0,
            too_long: false,
            skipped: 0,
            rejected: None,
        }
    }

    /// Forgets a partial sentence.
    pub fn clear(&mut self) {
        self.len = 0;
        self.in_sentence = false;
        self.too_long = false;
        self.skipped = 0;
        self.rejected = None;
    }

    /// Why the last line dropped since the previous sentence was dropped, if one was.
    pub fn take_rejected(&mut self) -> Option<Rejected> {
        self.rejected.take()
    }

    fn drop_partial(&mut self, why: Option<Rejected>) {
        if self.in_sentence {
            self.skipped += self.raw;
        }
        self.raw = 0;
        if why.is_some() {
            self.rejected = why;
        }
        self.len = 0;
        self.in_sentence = false;
        self.too_long = false;
    }

    /// Takes one byte that arrived at `arrived`; returns a sentence when this byte (an LF)
    /// completes one whose checksum matches.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Sentence<'_>> {
        match b {
            b'$' => {
                self.drop_partial(None);
                self.in_sentence = true;
                self.raw = 1;
                self.first = Some(arrived);
                None
            }
            _ if !self.in_sentence => {
                self.skipped += 1;
                None
            }
            b'\n' => {
                self.raw += 1;
                self.complete(arrived)
            }
            b'\r' => {
                self.raw += 1;
                None
            }
            _ => {
                self.raw += 1;
                if self.len == MAX_SENTENCE {
                    self.too_long = true;
                } else {
                    self.buf[self.len] = b;
                    self.len += 1;
                }
                None
            }
        }
    }

    fn complete(&mut self, arrived: Now) -> Option<Sentence<'_>> {
        if self.too_long {
            self.drop_partial(Some(Rejected::TooLong));
            return None;
        }
        let len = self.len;
        let star = self.buf[..len].iter().position(|&b| b == b'*');
        let body_end = star.unwrap_or(len);
        let ok = match star {
            None => true,
            Some(star) => {
                let x = self.buf[..star].iter().fold(0u8, |a, &b| a ^ b);
                let digits = &self.buf[star + 1..len];
                digits.len() == 2
                    && std::str::from_utf8(digits)
                        .ok()
                        .and_then(|d| u8::from_str_radix(d, 16).ok())
                        == Some(x)
            }
        };
        if !ok {
            self.drop_partial(Some(Rejected::Checksum));
            return None;
        }
        if std::str::from_utf8(&self.buf[..body_end]).is_err() {
            self.drop_partial(Some(Rejected::NotText));
            return None;
        }
        self.in_sentence = false;
        self.len = 0;
        self.raw = 0;
        let skipped = std::mem::take(&mut self.skipped);
        let body = std::str::from_utf8(&self.buf[..body_end]).unwrap_or("");
        Some(Sentence {
            body,
            first_byte: self.first.unwrap_or(arrived),
            skipped,
        })
    }
}

/// A position fix: latitude and longitude in degrees (south and west negative), altitude in
/// metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fix {
    /// Degrees north.
    pub lat: f64,
    /// Degrees east.
    pub lon: f64,
    /// Metres above mean sea level.
    pub alt: f64,
}

/// `DDMM.MMMM` (or `DDDMM.MMMM`) as decimal degrees, 0 to 180.
fn degrees(field: &str) -> Option<f64> {
    let v: f64 = field.parse().ok()?;
    let whole = (v / 100.0).trunc();
    let d = whole + (v - whole * 100.0) / 60.0;
    (0.0..=180.0).contains(&d).then_some(d)
}

/// The fix of a GGA sentence (any talker: `GPGGA`, `GNGGA`, …; exactly 15 fields, as C++
/// VRPN requires), if it has latitude, longitude and altitude. Other sentences give `None`.
pub fn parse_gga(body: &str) -> Option<Fix> {
    if body.len() < 5 || body.get(2..5) != Some("GGA") || body.split(',').count() != 15 {
        return None;
    }
    let mut it = body.split(',');
    let mut field = || it.next().unwrap_or("");
    let _talker = field();
    let _time = field();
    let (lat, ns) = (field(), field());
    let (lon, ew) = (field(), field());
    let (_quality, _sats, _hdop) = (field(), field(), field());
    let (alt, unit) = (field(), field());
    let lat = match ns {
        "N" => degrees(lat)?,
        "S" => -degrees(lat)?,
        _ => return None,
    };
    let lon = match ew {
        "E" => degrees(lon)?,
        "W" => -degrees(lon)?,
        _ => return None,
    };
    let alt: f64 = alt.parse().ok()?;
    let alt = match unit {
        "M" | "m" => alt,
        "F" | "f" => alt * METRES_PER_FOOT,
        _ => return None,
    };
    Some(Fix { lat, lon, alt })
}

/// The sentence type after the two talker letters (`RMC` of `GPRMC`), for notes.
pub fn kind(body: &str) -> &str {
    body.get(2..5).unwrap_or(body)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    #[test]
    fn gga_fixes_in_degrees_and_metres() {
        let f = parse_gga("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,").unwrap();
        assert_eq!(f.lat, 48.0 + (4807.038 - 4800.0) / 60.0);
        assert_eq!(f.lon, 11.0 + (1131.0 - 1100.0) / 60.0);
        assert_eq!(f.alt, 545.4);
        let f = parse_gga("GNGGA,1,3352.5,S,15112.5,W,1,08,0.9,100,F,0,M,,").unwrap();
        assert_eq!(f.lat, -(33.0 + (3352.5 - 3300.0) / 60.0));
        assert_eq!(f.lon, -(151.0 + 12.5 / 60.0));
        assert_eq!(f.alt, 100.0 * METRES_PER_FOOT);
        // No fix yet, a missing field, a sentence of another kind.
        assert_eq!(parse_gga("GPGGA,123519,,,,,0,00,,,M,,M,,"), None);
        assert_eq!(
            parse_gga("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M"),
            None
        );
        assert_eq!(
            parse_gga("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"),
            None
        );
    }

    #[test]
    fn sentences_are_found_after_garbage_and_checked() {
        let base = Instant::now();
        let at = |ms: u64| Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(5, 0).plus(Duration::from_millis(ms)),
        };
        let mut r = SentenceReader::new();
        let mut got = Vec::new();
        let mut feed = |bytes: &[u8], ms: u64, got: &mut Vec<(String, Now, usize)>| {
            for &b in bytes {
                if let Some(s) = r.push(b, at(ms)) {
                    got.push((s.body.to_owned(), s.first_byte, s.skipped));
                }
            }
        };
        feed(b"xx\n$GPGGA,1*", 0, &mut got);
        feed(b"$GPZDA,1*55\r\n", 1, &mut got);
        feed(b"$GPZDA,1*56\r\n", 2, &mut got);
        feed(b"$GPXYZ\r\n", 3, &mut got);
        assert_eq!(
            got,
            [
                ("GPZDA,1".to_owned(), at(1), 3 + 9),
                ("GPXYZ".to_owned(), at(3), 13)
            ]
        );
    }
}
