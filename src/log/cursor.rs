//! Reading a log's entries with bounded memory: a window of the file, refilled with positioned
//! reads as a walk moves on, so a file of any size costs one buffer (a log held in memory is
//! read in place).

use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;

use super::format::{decode_entry, entry_len, EntryHeader, EntryProblem, LogEntry};
use super::format::{ENTRY_HEADER_LEN, MAX_ENTRY_PAYLOAD};

/// Bytes of a file a cursor holds at once: several entries of the largest size, so that a
/// walk makes one read for many entries.
pub(crate) const WINDOW_LEN: usize = 256 * 1024;

const _: () = assert!(WINDOW_LEN >= 2 * entry_len(MAX_ENTRY_PAYLOAD));

/// Where a log's bytes are.
#[derive(Debug)]
pub(crate) enum Source {
    /// An open file, read with positioned reads (several cursors may share it).
    File(File),
    /// A whole file image in memory.
    Memory(Vec<u8>),
}

/// What went wrong reading the entry at an offset.
#[derive(Debug)]
pub(crate) enum CursorError {
    /// The bytes there are not a whole entry.
    Entry(EntryProblem),
    /// The operating system failed to read them.
    Io(io::Error),
}

/// A position-independent window onto a [`Source`]: `entry_at(offset)` decodes the entry
/// there, reading only what the window does not hold yet.
#[derive(Debug, Default)]
pub(crate) struct Cursor {
    /// The window (empty until a file is read; never used for a memory source).
    buf: Vec<u8>,
    /// File offset of `buf[0]`.
    start: u64,
    /// Bytes of `buf` holding file data.
    filled: usize,
    /// The end of the file was met right after `start + filled`.
    at_end: bool,
}

impl Cursor {
    /// A cursor whose window is allocated now (so that walking allocates nothing).
    pub(crate) fn with_window() -> Cursor {
        Cursor {
            buf: vec![0; WINDOW_LEN],
            ..Cursor::default()
        }
    }

    /// The entry at file offset `at` in `source`; `Ok(None)` at the end of the file.
    pub(crate) fn entry_at<'c>(
        &'c mut self,
        source: &'c Source,
        at: usize,
    ) -> Result<Option<LogEntry<'c>>, CursorError> {
        let head = self.bytes(source, at, ENTRY_HEADER_LEN)?;
        if head.is_empty() {
            return Ok(None);
        }
        let need = match EntryHeader::decode(head) {
            Ok(h) => entry_len(h.payload_len as usize),
            Err(p) => return Err(CursorError::Entry(p)),
        };
        let whole = self.bytes(source, at, need)?;
        decode_entry(whole, at)
            .map(Some)
            .map_err(CursorError::Entry)
    }

    /// At least `want` bytes from offset `at` (fewer only where the file ends), or whatever
    /// the window holds beyond that.
    fn bytes<'c>(
        &'c mut self,
        source: &'c Source,
        at: usize,
        want: usize,
    ) -> Result<&'c [u8], CursorError> {
        let file = match source {
            Source::Memory(bytes) => return Ok(bytes.get(at..).unwrap_or(&[])),
            Source::File(file) => file,
        };
        if self.buf.is_empty() {
            self.buf = vec![0; WINDOW_LEN];
        }
        let at = at as u64;
        let end = self.start + self.filled as u64;
        let held = at >= self.start && at <= end;
        if !(held && (at + want as u64 <= end || self.at_end)) {
            if held {
                // Keep what the window already holds from `at` on.
                let from = (at - self.start) as usize;
                self.buf.copy_within(from..self.filled, 0);
                self.filled -= from;
            } else {
                self.filled = 0;
            }
            self.start = at;
            self.at_end = false;
            self.fill(file, want)?;
        }
        let from = (at - self.start) as usize;
        Ok(&self.buf[from..self.filled])
    }

    /// Reads after what the window holds until it holds `want` bytes (reading as much as fits)
    /// or the file ends.
    fn fill(&mut self, file: &File, want: usize) -> Result<(), CursorError> {
        while self.filled < want.min(self.buf.len()) {
            let offset = self.start + self.filled as u64;
            match file.read_at(&mut self.buf[self.filled..], offset) {
                Ok(0) => {
                    self.at_end = true;
                    break;
                }
                Ok(n) => self.filled += n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(CursorError::Io(e)),
            }
        }
        Ok(())
    }

    /// The `len` bytes at file offset `at`, if the window holds them (the payload of the entry
    /// the last [`entry_at`](Self::entry_at) returned always is).
    pub(crate) fn held<'c>(
        &'c self,
        source: &'c Source,
        at: usize,
        len: usize,
    ) -> Option<&'c [u8]> {
        match source {
            Source::Memory(bytes) => bytes.get(at..at.checked_add(len)?),
            Source::File(_) => {
                let from = usize::try_from((at as u64).checked_sub(self.start)?).ok()?;
                self.buf[..self.filled].get(from..from.checked_add(len)?)
            }
        }
    }
}
