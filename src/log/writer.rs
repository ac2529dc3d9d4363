//! Writing a log file: the cookie, then entries, through a preallocated
//! in-memory buffer that a poll loop drains a bounded amount at a time.

use std::fs::{File, OpenOptions};
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};

use super::format::{encode_entry, entry_len, MAX_ENTRY_PAYLOAD};
use super::reader::LogError;
use crate::time::TimeVal;
use crate::wire::COOKIE_LEN;

/// Default size of a writer's buffer.
pub const DEFAULT_BUFFER_LEN: usize = 256 * 1024;

/// Smallest buffer a writer accepts: the cookie plus one entry of the largest payload, so any
/// message fits once the buffer is drained.
pub const MIN_BUFFER_LEN: usize = COOKIE_LEN + entry_len(MAX_ENTRY_PAYLOAD);

/// The cookie an incoming log stores for a peer: the peer's cookie bytes up to its first NUL,
/// the rest zero. At most 24 bytes of `peer` are used.
pub fn log_cookie_from_peer(peer: &[u8]) -> [u8; COOKIE_LEN] {
    let mut out = [0u8; COOKIE_LEN];
    for (o, &b) in out.iter_mut().zip(peer.iter().take_while(|&&b| b != 0)) {
        *o = b;
    }
    out
}

/// Writes a log: cookie first, then entries in C++'s byte format.
///
/// [`LogWriter::log_message`] appends to a buffer allocated once at construction and does not
/// touch the file unless the buffer is full, in which case it first writes out what is buffered.
/// [`LogWriter::flush_some`] writes a bounded amount so a poll loop never stalls for long;
/// [`LogWriter::flush_all`] writes everything. Dropping the writer flushes what is left,
/// ignoring errors; call [`LogWriter::finish`] to see them.
///
/// Generic over the sink so tests (and callers) may log into a `Vec<u8>`.
#[derive(Debug)]
pub struct LogWriter<W: Write = File> {
    out: Option<W>,
    path: PathBuf,
    buf: Box<[u8]>,
    /// First buffered byte not yet written.
    start: usize,
    /// End of buffered bytes.
    end: usize,
    written: usize,
    entries: u64,
}

impl LogWriter<File> {
    /// Creates the file at `path` with a [`DEFAULT_BUFFER_LEN`] buffer and buffers `cookie`.
    ///
    /// Like C++, never overwrites: an existing file is an error (`AlreadyExists`).
    pub fn create(
        path: impl AsRef<Path>,
        cookie: &[u8; COOKIE_LEN],
    ) -> Result<LogWriter<File>, LogError> {
        LogWriter::create_with_capacity(path, cookie, DEFAULT_BUFFER_LEN)
    }

    /// [`LogWriter::create`] with a chosen buffer size (raised to [`MIN_BUFFER_LEN`]).
    pub fn create_with_capacity(
        path: impl AsRef<Path>,
        cookie: &[u8; COOKIE_LEN],
        capacity: usize,
    ) -> Result<LogWriter<File>, LogError> {
        let path = path.as_ref();
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|error| LogError::Create {
                path: path.to_owned(),
                error,
            })?;
        Ok(LogWriter::new(file, path, cookie, capacity))
    }
}

impl<W: Write> LogWriter<W> {
    /// A writer into `out` with a `capacity`-byte buffer (raised to [`MIN_BUFFER_LEN`]), the
    /// cookie already buffered. `name` is used in error messages.
    pub fn new(
        out: W,
        name: impl Into<PathBuf>,
        cookie: &[u8; COOKIE_LEN],
        capacity: usize,
    ) -> LogWriter<W> {
        let mut buf = vec![0u8; capacity.max(MIN_BUFFER_LEN)].into_boxed_slice();
        buf[..COOKIE_LEN].copy_from_slice(cookie);
        LogWriter {
            out: Some(out),
            path: name.into(),
            buf,
            start: 0,
            end: COOKIE_LEN,
            written: 0,
            entries: 0,
        }
    }

    /// Replaces the cookie if none of it has reached the file yet (an incoming log learns its
    /// peer's cookie only when the peer connects). Returns whether it was replaced.
    pub fn set_cookie(&mut self, cookie: &[u8; COOKIE_LEN]) -> bool {
        if self.written == 0 && self.start == 0 {
            self.buf[..COOKIE_LEN].copy_from_slice(cookie);
            true
        } else {
            false
        }
    }

    /// Appends one entry: header (sixth word 0) and unpadded payload.
    ///
    /// Does not allocate. Writes to the file only when the buffer cannot take the entry.
    /// Fails on a payload over [`MAX_ENTRY_PAYLOAD`] (nothing is logged) or on a write error.
    pub fn log_message(
        &mut self,
        type_id: i32,
        sender: i32,
        time: TimeVal,
        payload: &[u8],
    ) -> Result<(), LogError> {
        if payload.len() > MAX_ENTRY_PAYLOAD {
            return Err(LogError::PayloadTooLong {
                path: self.path.clone(),
                len: payload.len(),
            });
        }
        let need = entry_len(payload.len());
        self.make_room(need)?;
        match encode_entry(&mut self.buf[self.end..], type_id, sender, time, payload) {
            Some(n) => {
                self.end += n;
                self.entries += 1;
                Ok(())
            }
            // Unreachable: make_room guaranteed the space and the length was checked above.
            None => Err(LogError::PayloadTooLong {
                path: self.path.clone(),
                len: payload.len(),
            }),
        }
    }

    fn make_room(&mut self, need: usize) -> Result<(), LogError> {
        if self.buf.len() - self.end >= need {
            return Ok(());
        }
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
            if self.buf.len() - self.end >= need {
                return Ok(());
            }
        }
        // Everything goes out; the buffer then holds at least MIN_BUFFER_LEN free bytes.
        self.flush_all()
    }

    /// Writes at most `max_bytes` of the buffered bytes to the sink. Returns the bytes written,
    /// fewer than asked when the buffer empties or the sink reports `WouldBlock`.
    pub fn flush_some(&mut self, max_bytes: usize) -> Result<usize, LogError> {
        let mut done = 0;
        while done < max_bytes && self.start < self.end {
            let Some(out) = self.out.as_mut() else {
                break;
            };
            let chunk = (self.end - self.start).min(max_bytes - done);
            match out.write(&self.buf[self.start..self.start + chunk]) {
                Ok(0) => {
                    return Err(self.io_error(std::io::Error::from(ErrorKind::WriteZero)));
                }
                Ok(n) => {
                    let n = n.min(chunk);
                    self.start += n;
                    self.written += n;
                    done += n;
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) => return Err(self.io_error(e)),
            }
        }
        if self.start == self.end {
            self.start = 0;
            self.end = 0;
        }
        Ok(done)
    }

    /// Writes everything buffered and flushes the sink.
    pub fn flush_all(&mut self) -> Result<(), LogError> {
        while self.start < self.end {
            if self.flush_some(usize::MAX)? == 0 {
                // A sink that would block: nothing else to do but retry.
                std::thread::yield_now();
            }
        }
        if let Some(out) = self.out.as_mut() {
            if let Err(e) = out.flush() {
                return Err(self.io_error(e));
            }
        }
        Ok(())
    }

    /// Flushes everything and returns the sink.
    pub fn finish(mut self) -> Result<W, LogError> {
        self.flush_all()?;
        match self.out.take() {
            Some(out) => Ok(out),
            None => Err(self.io_error(std::io::Error::other("log sink already taken"))),
        }
    }

    fn io_error(&self, error: std::io::Error) -> LogError {
        LogError::Io {
            path: self.path.clone(),
            offset: self.written,
            error,
        }
    }

    /// The file path (or name) used in error messages.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes buffered and not yet written.
    pub fn pending(&self) -> usize {
        self.end - self.start
    }

    /// Bytes written to the sink so far, the cookie included.
    pub fn bytes_written(&self) -> usize {
        self.written
    }

    /// Entries logged so far.
    pub fn entries_logged(&self) -> u64 {
        self.entries
    }

    /// Size of the buffer.
    pub fn capacity(&self) -> usize {
        self.buf.len()
    }

    /// The sink.
    pub fn get_ref(&self) -> Option<&W> {
        self.out.as_ref()
    }
}

impl<W: Write> Drop for LogWriter<W> {
    fn drop(&mut self) {
        if self.out.is_some() {
            let _ = self.flush_all();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::reader::LogReader;
    use crate::wire::Cookie;

    #[test]
    fn peer_cookie_is_cut_at_nul() {
        let c = log_cookie_from_peer(b"vrpn: ver. 07.35  3\0junk");
        assert_eq!(&c, b"vrpn: ver. 07.35  3\0\0\0\0\0");
        assert_eq!(
            log_cookie_from_peer(b"ab"),
            *b"ab\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
        );
    }

    #[test]
    fn writes_cookie_and_entries_with_bounded_flushes() {
        let cookie = Cookie::ours(0).to_bytes();
        let mut w = LogWriter::new(Vec::new(), "mem", &cookie, 0);
        assert_eq!(w.capacity(), MIN_BUFFER_LEN);
        for i in 0..10_000i32 {
            w.log_message(4, 1, TimeVal::new(7, i as i64), &i.to_be_bytes())
                .unwrap();
            let before = w.bytes_written();
            let n = w.flush_some(5).unwrap();
            assert!(n <= 5);
            assert_eq!(w.bytes_written(), before + n);
        }
        assert_eq!(w.entries_logged(), 10_000);
        let bytes = w.finish().unwrap();
        assert_eq!(bytes.len(), 24 + 10_000 * 28);
        let r = LogReader::from_bytes(bytes, "mem").unwrap();
        let mut entries = r.entries();
        let mut i = 0i32;
        while let Some(e) = entries.next_entry() {
            let e = e.unwrap();
            assert_eq!(e.payload, &i.to_be_bytes());
            assert_eq!(e.time(), TimeVal::new(7, i64::from(i)));
            i += 1;
        }
        assert_eq!(r.entries().count_whole(), 10_000);
    }

    #[test]
    fn full_buffer_spills_and_big_payload_is_refused() {
        let cookie = Cookie::ours(0).to_bytes();
        let mut w = LogWriter::new(Vec::new(), "mem", &cookie, 0);
        let big = vec![7u8; MAX_ENTRY_PAYLOAD];
        for _ in 0..5 {
            w.log_message(1, 2, TimeVal::ZERO, &big).unwrap();
        }
        assert!(w.bytes_written() > 0);
        let err = w
            .log_message(1, 2, TimeVal::ZERO, &vec![0; MAX_ENTRY_PAYLOAD + 1])
            .unwrap_err();
        assert!(matches!(err, LogError::PayloadTooLong { .. }));
        let bytes = w.finish().unwrap();
        assert_eq!(bytes.len(), 24 + 5 * entry_len(MAX_ENTRY_PAYLOAD));
    }

    #[test]
    fn set_cookie_only_before_first_write() {
        let mut w = LogWriter::new(Vec::new(), "mem", &Cookie::ours(0).to_bytes(), 0);
        let peer = log_cookie_from_peer(b"vrpn: ver. 07.35  1\0");
        assert!(w.set_cookie(&peer));
        w.flush_some(3).unwrap();
        assert!(!w.set_cookie(&Cookie::ours(0).to_bytes()));
        let bytes = w.finish().unwrap();
        assert_eq!(&bytes[..], &peer[..]);
    }

    #[test]
    fn file_is_created_once_and_flushed_on_drop() {
        let dir = std::env::temp_dir().join(format!("vrpn-log-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("drop.vrpn");
        let _ = std::fs::remove_file(&path);
        {
            let mut w = LogWriter::create(&path, &Cookie::ours(0).to_bytes()).unwrap();
            w.log_message(-5, 0, TimeVal::new(1, 2), &[]).unwrap();
            let err = LogWriter::create(&path, &Cookie::ours(0).to_bytes()).unwrap_err();
            assert!(
                matches!(&err, LogError::Create { error, .. } if error.kind() == ErrorKind::AlreadyExists)
            );
        }
        let r = LogReader::open(&path).unwrap();
        let mut entries = r.entries();
        assert_eq!(entries.next_entry().unwrap().unwrap().type_id(), -5);
        assert!(entries.next_entry().is_none());
        std::fs::remove_file(&path).unwrap();
        let _ = std::fs::remove_dir(&dir);
    }
}
