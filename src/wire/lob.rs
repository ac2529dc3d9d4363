//! The UDP connection request ("lob" packet) a client sends to a server's UDP port: the text
//! `IP PORT` and a NUL, naming where the server should connect back.

use super::{Result, WireError};

/// Largest request a C++ server reads (200-byte buffer, 199 used).
pub const MAX_REQUEST: usize = 199;

/// Writes the request into `out`; returns its length including the NUL.
pub fn encode_request(out: &mut [u8], host: &str, port: u16) -> usize {
    use std::io::Write;
    let mut cursor = std::io::Cursor::new(&mut out[..]);
    // Writing into a slice cannot fail short of running out of room, which the caller sizes.
    let _ = write!(cursor, "{host} {port}\0");
    cursor.position() as usize
}

/// A parsed connection request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request<'a> {
    /// Host to connect back to, as the client wrote it.
    pub host: &'a str,
    /// TCP port to connect back to.
    pub port: u16,
}

/// Parses a request with the rules a C++ server applies: two whitespace-separated fields, host
/// of `[A-Za-z0-9.]` only, port at least 1024.
pub fn parse_request(datagram: &[u8]) -> Result<Request<'_>> {
    let text = &datagram[..datagram.len().min(MAX_REQUEST)];
    let text = match text.iter().position(|&b| b == 0) {
        Some(n) => &text[..n],
        None => text,
    };
    let text = std::str::from_utf8(text).map_err(|_| WireError::BadValue("request text"))?;
    let mut fields = text.split_ascii_whitespace();
    let host = fields.next().ok_or(WireError::BadValue("request host"))?;
    let port = fields.next().ok_or(WireError::BadValue("request port"))?;
    if !host.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'.') {
        return Err(WireError::BadValue("request host"));
    }
    let port: u16 = port
        .parse()
        .map_err(|_| WireError::BadValue("request port"))?;
    if port < 1024 {
        return Err(WireError::BadValue("request port below 1024"));
    }
    Ok(Request { host, port })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_cpp_request() {
        let mut buf = [0u8; 64];
        let n = encode_request(&mut buf, "127.0.0.1", 48615);
        assert_eq!(&buf[..n], b"127.0.0.1 48615\0");
        let r = parse_request(&buf[..n]).unwrap();
        assert_eq!(
            r,
            Request {
                host: "127.0.0.1",
                port: 48615
            }
        );
    }

    #[test]
    fn refuses_what_cpp_refuses() {
        assert!(parse_request(b"127.0.0.1 80\0").is_err());
        assert!(parse_request(b"my-host 5000\0").is_err());
        assert!(parse_request(b"justonefield\0").is_err());
        assert!(parse_request(b"").is_err());
    }
}
