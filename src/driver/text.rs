//! Text messages formatted on the stack, so drivers can report problems while streaming
//! without allocating.

use std::fmt::{self, Write as _};

/// Longest message kept; longer text is cut at a character boundary.
const CAPACITY: usize = 320;

/// Formats `args` into a fixed buffer and hands the text to `send`.
pub fn with_text(args: fmt::Arguments<'_>, send: impl FnOnce(&str)) {
    let mut text = TextBuf {
        buf: [0; CAPACITY],
        len: 0,
    };
    let _ = text.write_fmt(args);
    send(text.as_str());
}

/// A byte as it is shown in messages: the character if printable, else its hex value.
pub struct Shown(pub u8);

impl fmt::Display for Shown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_ascii_graphic() || self.0 == b' ' {
            write!(f, "'{}'", self.0 as char)
        } else {
            write!(f, "0x{:02X}", self.0)
        }
    }
}

/// Bytes as they are shown in messages: printable ASCII as it is, the rest escaped.
pub struct ShownBytes<'a>(pub &'a [u8]);

impl fmt::Display for ShownBytes<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for &b in self.0 {
            match b {
                b'\r' => f.write_str("\\r")?,
                b'\n' => f.write_str("\\n")?,
                b if b.is_ascii_graphic() || b == b' ' => f.write_char(b as char)?,
                b => write!(f, "\\x{b:02X}")?,
            }
        }
        Ok(())
    }
}

struct TextBuf {
    buf: [u8; CAPACITY],
    len: usize,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_and_cuts_at_a_character_boundary() {
        let mut got = String::new();
        with_text(format_args!("a {} {}", Shown(b'x'), Shown(0x0D)), |t| {
            got = t.to_owned()
        });
        assert_eq!(got, "a 'x' 0x0D");
        with_text(format_args!("{}", ShownBytes(b"z\rm3\x01")), |t| {
            got = t.to_owned()
        });
        assert_eq!(got, "z\\rm3\\x01");
        let long = "é".repeat(200);
        with_text(format_args!("{long}"), |t| got = t.to_owned());
        assert_eq!(got.len(), CAPACITY);
        assert!(got.chars().all(|c| c == 'é'));
    }
}
