//! Text messages formatted on the stack, so a driver can send a note from its steady-state
//! path without allocating.

use std::fmt::{self, Write as _};

/// One text message; longer text is cut at a character boundary (VRPN texts are short).
pub struct TextBuf {
    buf: [u8; 320],
    len: usize,
}

impl TextBuf {
    /// `args`, formatted.
    pub fn format(args: fmt::Arguments<'_>) -> TextBuf {
        let mut t = TextBuf {
            buf: [0; 320],
            len: 0,
        };
        let _ = t.write_fmt(args);
        t
    }

    /// The text.
    pub fn as_str(&self) -> &str {
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
