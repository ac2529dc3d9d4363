//! Fixed-size text fields: C++ structs that carry a `char name[N]` copy all `N` bytes onto
//! the wire, the text NUL-terminated inside them and whatever the array held after the NUL.

use super::super::{need, Result, WireError};

/// A `char[N]` field: the text ends at the first NUL (or fills all `N` bytes when a peer sent
/// none). The raw bytes are kept as decoded, so re-encoding gives back the same payload.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct FixedText<const N: usize> {
    raw: [u8; N],
}

impl<const N: usize> Default for FixedText<N> {
    fn default() -> Self {
        FixedText { raw: [0; N] }
    }
}

impl<const N: usize> std::fmt::Debug for FixedText<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}", String::from_utf8_lossy(self.as_bytes()))
    }
}

impl<const N: usize> FixedText<N> {
    /// Bytes on the wire.
    pub const LEN: usize = N;

    /// A field holding `text` (at most `N - 1` bytes, no NUL), zero-filled after it.
    pub fn new(text: &str) -> Result<FixedText<N>> {
        let b = text.as_bytes();
        if b.len() >= N {
            return Err(WireError::BadValue("text longer than its fixed-size field"));
        }
        if b.contains(&0) {
            return Err(WireError::BadValue("text with an embedded NUL"));
        }
        let mut raw = [0; N];
        raw[..b.len()].copy_from_slice(b);
        Ok(FixedText { raw })
    }

    /// The text: the bytes before the first NUL.
    pub fn as_bytes(&self) -> &[u8] {
        let n = self.raw.iter().position(|&b| b == 0).unwrap_or(N);
        &self.raw[..n]
    }

    /// The text as UTF-8, if it is.
    pub fn as_str(&self) -> Option<&str> {
        std::str::from_utf8(self.as_bytes()).ok()
    }

    /// The text, invalid UTF-8 replaced.
    pub fn to_string_lossy(&self) -> String {
        String::from_utf8_lossy(self.as_bytes()).into_owned()
    }

    /// All `N` bytes as on the wire.
    pub fn raw(&self) -> &[u8; N] {
        &self.raw
    }

    /// Reads the field from the start of `buf`.
    pub fn decode(buf: &[u8]) -> Result<FixedText<N>> {
        need(buf, N)?;
        let mut raw = [0; N];
        raw.copy_from_slice(&buf[..N]);
        Ok(FixedText { raw })
    }

    /// Writes all `N` bytes at the start of `out`; returns `N`.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        out[..N].copy_from_slice(&self.raw);
        N
    }
}

impl<const N: usize> super::Field for FixedText<N> {
    const SIZE: usize = N;
    fn read(buf: &[u8]) -> Self {
        let mut raw = [0; N];
        raw.copy_from_slice(&buf[..N]);
        FixedText { raw }
    }
    fn write(&self, buf: &mut [u8]) {
        buf[..N].copy_from_slice(&self.raw);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_ends_at_nul_and_raw_bytes_survive() {
        let t = FixedText::<8>::new("abc").unwrap();
        assert_eq!(t.as_bytes(), b"abc");
        assert_eq!(t.raw(), b"abc\0\0\0\0\0");
        assert!(FixedText::<4>::new("abcd").is_err());
        assert!(FixedText::<8>::new("a\0b").is_err());
        let wire = *b"xy\0garba";
        let d = FixedText::<8>::decode(&wire).unwrap();
        assert_eq!(d.as_str(), Some("xy"));
        let mut out = [0u8; 8];
        assert_eq!(d.encode(&mut out), 8);
        assert_eq!(out, wire);
        // No NUL at all: the whole field is the text.
        assert_eq!(FixedText::<3>::decode(b"abc").unwrap().as_bytes(), b"abc");
        assert!(FixedText::<8>::decode(b"short").is_err());
    }
}
