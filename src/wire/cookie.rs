//! The 24-byte cookie both sides send first on every TCP connection, and that opens every log
//! file.

use super::{need, Result};

/// Size of the cookie: 16 magic bytes plus 8 (two spaces, log-mode digit, NULs).
pub const COOKIE_LEN: usize = 24;
/// The magic we announce: the current C++ release.
pub const MAGIC: &[u8; 16] = b"vrpn: ver. 07.38";
/// Magic of a log file written by VRPN (the same text; logs carry the writer's cookie).
pub const FILE_MAGIC: &[u8; 16] = MAGIC;

/// A decoded cookie.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cookie {
    /// The peer's 16-byte magic, e.g. `vrpn: ver. 07.35`.
    pub magic: [u8; 16],
    /// Log mode the peer asks of us: bit 0 log your incoming, bit 1 log your outgoing.
    pub log_mode: u8,
}

/// Why a peer's cookie was refused (the connection is dropped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CookieError {
    /// Not a VRPN 07 peer: the text up to the last `.` differs from ours.
    BadMagic([u8; 16]),
    /// The log-mode digit is not `'0'`..`'3'`.
    BadLogMode(u8),
}

impl std::fmt::Display for CookieError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CookieError::BadMagic(m) => write!(
                f,
                "bad cookie {:?}: not a VRPN 07.x peer (we speak {})",
                String::from_utf8_lossy(m),
                String::from_utf8_lossy(MAGIC)
            ),
            CookieError::BadLogMode(c) => {
                write!(f, "bad cookie: log mode byte {c:#04x} is not '0'..'3'")
            }
        }
    }
}

impl std::error::Error for CookieError {}

impl Cookie {
    /// Our cookie with the given remote log mode (0 unless we ask the peer to log for us).
    pub fn ours(log_mode: u8) -> Cookie {
        Cookie {
            magic: *MAGIC,
            log_mode,
        }
    }

    /// The 24 bytes sent on the wire.
    pub fn to_bytes(&self) -> [u8; COOKIE_LEN] {
        let mut out = [0u8; COOKIE_LEN];
        out[..16].copy_from_slice(&self.magic);
        out[16] = b' ';
        out[17] = b' ';
        out[18] = b'0' + (self.log_mode & 3);
        out
    }

    /// Decodes a cookie without judging it (log readers want to see any magic).
    pub fn parse(buf: &[u8]) -> Result<Cookie> {
        need(buf, COOKIE_LEN)?;
        let mut magic = [0u8; 16];
        magic.copy_from_slice(&buf[..16]);
        Ok(Cookie {
            magic,
            log_mode: buf[18].wrapping_sub(b'0'),
        })
    }

    /// Applies the C++ acceptance rules: the major version must match (compared up to the last
    /// `.` of the received text), the log mode must be 0..=3. A different minor version is
    /// accepted; [`Cookie::minor_differs`] tells the caller to warn.
    pub fn check(&self) -> std::result::Result<(), CookieError> {
        let major_end = match self.magic.iter().rposition(|&b| b == b'.') {
            Some(i) => i + 1,
            None => return Err(CookieError::BadMagic(self.magic)),
        };
        if self.magic[..major_end] != MAGIC[..major_end] {
            return Err(CookieError::BadMagic(self.magic));
        }
        if self.log_mode > 3 {
            return Err(CookieError::BadLogMode(self.log_mode.wrapping_add(b'0')));
        }
        Ok(())
    }

    /// True when the peer runs another 07 minor version (worth a warning, not a refusal).
    pub fn minor_differs(&self) -> bool {
        self.magic != *MAGIC
    }

    /// The version text, e.g. `07.35`.
    pub fn version(&self) -> String {
        String::from_utf8_lossy(&self.magic[11..16]).into_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn our_cookie_matches_cpp_bytes() {
        let bytes = Cookie::ours(0).to_bytes();
        let expected = b"vrpn: ver. 07.38  0\0\0\0\0\0";
        assert_eq!(&bytes, expected);
    }

    #[test]
    fn accepts_other_minor_rejects_other_major() {
        let mut c = Cookie::parse(b"vrpn: ver. 07.35  0\0\0\0\0\0").unwrap();
        assert!(c.check().is_ok());
        assert!(c.minor_differs());
        c.magic = *b"vrpn: ver. 08.00";
        assert!(matches!(c.check(), Err(CookieError::BadMagic(_))));
        let c = Cookie::parse(b"vrpn: ver. 07.38  7\0\0\0\0\0").unwrap();
        assert!(matches!(c.check(), Err(CookieError::BadLogMode(b'7'))));
        let c = Cookie::parse(b"HTTP/1.1 200 OK\r\n\r\nabcde").unwrap();
        assert!(c.check().is_err());
    }
}
