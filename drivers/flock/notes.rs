//! Text messages from the tracker, formatted on the stack (no allocation).

use std::fmt::{self, Write as _};

use crate::devices::text::TextSeverity;
use crate::TrackerServer;

/// Formats `args` into a fixed buffer and sends it as a text message from `tracker`.
pub fn say(tracker: &TrackerServer, severity: TextSeverity, args: fmt::Arguments<'_>) {
    let mut text = TextBuf::default();
    let _ = text.write_fmt(args);
    // A failed send is the connection's business (it reports and drops the peer).
    let _ = tracker.send_text(severity, 0, text.as_str());
}

/// A fixed buffer for one message; longer text is cut at a character boundary.
struct TextBuf {
    buf: [u8; 320],
    len: usize,
}

impl Default for TextBuf {
    fn default() -> TextBuf {
        TextBuf {
            buf: [0; 320],
            len: 0,
        }
    }
}

impl TextBuf {
    fn as_str(&self) -> &str {
        // Only whole characters are ever copied in.
        std::str::from_utf8(&self.buf[..self.len]).unwrap_or("")
    }
}

impl fmt::Write for TextBuf {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let room = self.buf.len() - self.len;
        let mut n = s.len().min(room);
        while !s.is_char_boundary(n) {
            n -= 1;
        }
        self.buf[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

/// The units a system-status answer shows as not accessible or not running, as
/// "address 2 not running, address 3 not accessible".
pub struct UnitsDown<'a> {
    /// The system-status bytes (one per bus address from 1).
    pub status: &'a [u8],
    /// Units that must be up (addresses 1..=units).
    pub units: u8,
}

impl fmt::Display for UnitsDown<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use super::reset::{UNIT_ACCESSIBLE, UNIT_RUNNING};
        let mut first = true;
        for (i, &s) in self.status.iter().take(usize::from(self.units)).enumerate() {
            let what = if s & UNIT_ACCESSIBLE == 0 {
                "not accessible"
            } else if s & UNIT_RUNNING == 0 {
                "not running"
            } else {
                continue;
            };
            if !first {
                f.write_str(", ")?;
            }
            first = false;
            write!(f, "address {} {what}", i + 1)?;
        }
        Ok(())
    }
}

/// Why a reset failed, in words.
pub struct FailureText {
    /// The failure.
    pub failure: super::reset::Failure,
    /// Units the status check covered.
    pub units: u8,
}

impl fmt::Display for FailureText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use super::reset::{Failure, STATUS_LEN};
        match self.failure {
            Failure::NoAnswer => f.write_str(
                "Flock reset failed: the master bird does not answer (check its power, the \
                 cable and the baud rate)",
            ),
            Failure::NeverQuiet => f.write_str(
                "Flock reset failed: the line kept sending after the stop command (check the \
                 baud rate)",
            ),
            Failure::StatusIncomplete(got) => write!(
                f,
                "Flock reset failed: received only {got} of {STATUS_LEN} bytes of the system \
                 status"
            ),
            Failure::UnitsDown(status) => write!(
                f,
                "Flock reset failed: {} (check that every unit is switched to FLY)",
                UnitsDown {
                    status: &status,
                    units: self.units,
                }
            ),
        }
    }
}
