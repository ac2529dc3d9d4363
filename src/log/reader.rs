//! Reading a log file: cookie check, then entries one by one as borrowed
//! views, stopping cleanly at the first damaged byte.

use std::os::unix::fs::{FileExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

use super::cursor::{Cursor, CursorError, Source};
use super::format::{EntryProblem, LogEntry};
use crate::wire::{Cookie, COOKIE_LEN};

/// Why a log file's cookie was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CookieProblem {
    /// The file is shorter than the 24-byte cookie.
    Truncated {
        /// Bytes present.
        available: usize,
    },
    /// The first 16 bytes are not a VRPN version text of major 04 to 07.
    BadMagic([u8; 16]),
}

impl std::fmt::Display for CookieProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CookieProblem::Truncated { available } => write!(
                f,
                "file too short for the {COOKIE_LEN}-byte cookie ({available} bytes)"
            ),
            CookieProblem::BadMagic(m) => write!(
                f,
                "not a VRPN 04..07 log: cookie reads {:?}",
                String::from_utf8_lossy(m)
            ),
        }
    }
}

/// Checks a log file's cookie as C++ `check_vrpn_file_cookie` does: the text up to the last `.`
/// must read `vrpn: ver. MM.` with `04 ≤ MM ≤ 07`. Any minor version and any log-mode character
/// are accepted (an incoming log carries the peer's cookie).
pub fn check_log_cookie(file: &[u8]) -> Result<Cookie, CookieProblem> {
    let Some(bytes) = file.get(..COOKIE_LEN) else {
        return Err(CookieProblem::Truncated {
            available: file.len(),
        });
    };
    let cookie = Cookie::parse(bytes).map_err(|_| CookieProblem::Truncated {
        available: file.len(),
    })?;
    let prefix = match bytes.iter().rposition(|&b| b == b'.') {
        Some(i) => &bytes[..=i],
        None => return Err(CookieProblem::BadMagic(cookie.magic)),
    };
    let ok = prefix.len() == 14
        && prefix.starts_with(b"vrpn: ver. ")
        && (b"04".as_slice()..=b"07".as_slice()).contains(&&prefix[11..13]);
    if ok {
        Ok(cookie)
    } else {
        Err(CookieProblem::BadMagic(cookie.magic))
    }
}

/// Why a log could not be read or written past some point.
///
/// Every variant names the file and, where it applies, the byte offset; `Display` gives
/// `PATH: byte OFFSET: problem`.
#[derive(Debug)]
#[non_exhaustive]
pub enum LogError {
    /// An operating-system error while opening, reading or writing the file.
    Io {
        /// The file.
        path: PathBuf,
        /// Offset reached in the file (bytes read or written so far).
        offset: usize,
        /// The error.
        error: std::io::Error,
    },
    /// The cookie at offset 0 is missing or not a VRPN log cookie.
    BadCookie {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: CookieProblem,
    },
    /// An entry is truncated or corrupt; every entry before `offset` was whole.
    BadEntry {
        /// The file.
        path: PathBuf,
        /// File offset of the damaged entry.
        offset: usize,
        /// What is wrong.
        problem: EntryProblem,
    },
    /// The path names something other than a regular file (a FIFO, a device, a directory):
    /// logs are read only from regular files, so opening never blocks and reading ends.
    NotARegularFile {
        /// The path.
        path: PathBuf,
        /// What it names ("a FIFO", "a character device", …).
        kind: &'static str,
    },
    /// A message too large for a log entry was offered to a writer.
    PayloadTooLong {
        /// The file.
        path: PathBuf,
        /// The refused payload length.
        len: usize,
    },
    /// The log file to read cannot be opened (no such file, permission denied, …).
    Open {
        /// The file.
        path: PathBuf,
        /// The error.
        error: std::io::Error,
    },
    /// A new log file cannot be created (it exists already, its folder does not, …).
    Create {
        /// The file.
        path: PathBuf,
        /// The error.
        error: std::io::Error,
    },
}

impl LogError {
    /// The file concerned.
    pub fn path(&self) -> &Path {
        match self {
            LogError::Io { path, .. }
            | LogError::BadCookie { path, .. }
            | LogError::BadEntry { path, .. }
            | LogError::NotARegularFile { path, .. }
            | LogError::PayloadTooLong { path, .. }
            | LogError::Open { path, .. }
            | LogError::Create { path, .. } => path,
        }
    }

    /// The byte offset concerned, where one applies.
    pub fn offset(&self) -> Option<usize> {
        match self {
            LogError::Io { offset, .. } | LogError::BadEntry { offset, .. } => Some(*offset),
            LogError::BadCookie { .. } | LogError::NotARegularFile { .. } => Some(0),
            LogError::PayloadTooLong { .. } | LogError::Open { .. } | LogError::Create { .. } => {
                None
            }
        }
    }

    pub(crate) fn from_cursor(path: &Path, offset: usize, e: CursorError) -> LogError {
        match e {
            CursorError::Entry(problem) => LogError::BadEntry {
                path: path.to_owned(),
                offset,
                problem,
            },
            CursorError::Io(error) => LogError::Io {
                path: path.to_owned(),
                offset,
                error,
            },
        }
    }
}

impl std::fmt::Display for LogError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let path = self.path().display();
        match self {
            LogError::Io { offset, error, .. } => write!(f, "{path}: byte {offset}: {error}"),
            LogError::BadCookie { problem, .. } => write!(f, "{path}: byte 0: {problem}"),
            LogError::BadEntry {
                offset, problem, ..
            } => write!(f, "{path}: byte {offset}: {problem}"),
            LogError::NotARegularFile { kind, .. } => write!(
                f,
                "{path}: byte 0: {kind}, not a regular file (logs are read from regular files \
                 only)"
            ),
            LogError::PayloadTooLong { len, .. } => write!(
                f,
                "{path}: message payload of {len} bytes is too long for a log entry (limit {})",
                super::format::MAX_ENTRY_PAYLOAD
            ),
            LogError::Open { error, .. } => {
                write!(f, "cannot read log file {path}: {}", open_problem(error))
            }
            LogError::Create { path, error } => {
                write!(f, "cannot create log file {}: ", path.display())?;
                create_problem(f, path, error)
            }
        }
    }
}

/// Why a log file could not be opened for reading, in words.
fn open_problem(error: &std::io::Error) -> String {
    match error.kind() {
        std::io::ErrorKind::NotFound => "no such file".to_owned(),
        std::io::ErrorKind::PermissionDenied => "permission denied".to_owned(),
        _ => error.to_string(),
    }
}

/// Why a new log file could not be created, in words.
fn create_problem(
    f: &mut std::fmt::Formatter<'_>,
    path: &Path,
    error: &std::io::Error,
) -> std::fmt::Result {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.display().to_string(),
        _ => ".".to_owned(),
    };
    match error.kind() {
        std::io::ErrorKind::AlreadyExists => f.write_str(
            "it exists already (a log is never overwritten: choose another name or move the \
             old file away)",
        ),
        std::io::ErrorKind::NotFound => write!(f, "folder {folder} does not exist"),
        std::io::ErrorKind::PermissionDenied => {
            write!(f, "permission denied (cannot write in folder {folder})")
        }
        _ => write!(f, "{error}"),
    }
}

impl std::error::Error for LogError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LogError::Io { error, .. }
            | LogError::Open { error, .. }
            | LogError::Create { error, .. } => Some(error),
            _ => None,
        }
    }
}

/// A log file with its cookie checked, read entry by entry with bounded memory.
///
/// [`LogReader::open`] reads the 24-byte cookie and nothing more; [`LogReader::entries`] then
/// walks the file through a window of a few hundred kilobytes, whatever its size (C++ reads
/// the whole file into memory first). Several walks may run at once, each with its own window.
/// Only regular files are read: opening a FIFO, a device or a directory fails at once with
/// [`LogError::NotARegularFile`] instead of blocking or reading without end.
#[derive(Debug)]
pub struct LogReader {
    path: PathBuf,
    source: Source,
    len: u64,
    cookie: Cookie,
    cookie_bytes: [u8; COOKIE_LEN],
}

impl LogReader {
    /// Opens the file at `path` and checks its cookie. Never blocks: the file is opened
    /// non-blocking and must be a regular file.
    pub fn open(path: impl AsRef<Path>) -> Result<LogReader, LogError> {
        let path = path.as_ref();
        let open = |error| LogError::Open {
            path: path.to_owned(),
            error,
        };
        let file = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(nix::libc::O_NONBLOCK)
            .open(path)
            .map_err(open)?;
        let meta = file.metadata().map_err(open)?;
        if !meta.file_type().is_file() {
            return Err(LogError::NotARegularFile {
                path: path.to_owned(),
                kind: file_kind(meta.file_type()),
            });
        }
        let mut cookie = [0u8; COOKIE_LEN];
        let mut got = 0;
        while got < COOKIE_LEN {
            match file.read_at(&mut cookie[got..], got as u64) {
                Ok(0) => break,
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(error) => {
                    return Err(LogError::Io {
                        path: path.to_owned(),
                        offset: got,
                        error,
                    })
                }
            }
        }
        LogReader::checked(
            &cookie[..got],
            path.to_owned(),
            Source::File(file),
            meta.len(),
        )
    }

    /// Takes a file image already in memory; `name` is used in error messages.
    pub fn from_bytes(bytes: Vec<u8>, name: impl Into<PathBuf>) -> Result<LogReader, LogError> {
        let len = bytes.len() as u64;
        let head = bytes[..bytes.len().min(COOKIE_LEN)].to_vec();
        LogReader::checked(&head, name.into(), Source::Memory(bytes), len)
    }

    fn checked(
        head: &[u8],
        path: PathBuf,
        source: Source,
        len: u64,
    ) -> Result<LogReader, LogError> {
        match check_log_cookie(head) {
            Ok(cookie) => {
                let mut cookie_bytes = [0u8; COOKIE_LEN];
                cookie_bytes.copy_from_slice(&head[..COOKIE_LEN]);
                Ok(LogReader {
                    path,
                    source,
                    len,
                    cookie,
                    cookie_bytes,
                })
            }
            Err(problem) => Err(LogError::BadCookie { path, problem }),
        }
    }

    /// The file's path (or the name given to [`LogReader::from_bytes`]).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The decoded cookie.
    pub fn cookie(&self) -> &Cookie {
        &self.cookie
    }

    /// The cookie's 24 bytes as stored (what a re-log during replay writes).
    pub fn cookie_bytes(&self) -> &[u8; COOKIE_LEN] {
        &self.cookie_bytes
    }

    /// The file's length in bytes when it was opened.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// True for a file of no more than its cookie.
    pub fn is_empty(&self) -> bool {
        self.len <= COOKIE_LEN as u64
    }

    /// Walks the entries from the first one.
    pub fn entries(&self) -> Entries<'_> {
        self.entries_from(COOKIE_LEN)
    }

    /// Walks the entries starting at file offset `offset`, which must be an entry boundary
    /// (e.g. a saved [`Entries::offset`]); an offset past the end yields nothing.
    pub fn entries_from(&self, offset: usize) -> Entries<'_> {
        Entries {
            reader: self,
            cursor: Cursor::default(),
            next: offset.max(COOKIE_LEN),
            done: false,
        }
    }

    pub(crate) fn source(&self) -> &Source {
        &self.source
    }
}

/// What kind of file a path names, for the error that refuses anything but a regular file.
fn file_kind(t: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// The entries of a [`LogReader`], in file order: a lending iterator, each entry borrowing the
/// walk's window until the next call.
///
/// [`Entries::next_entry`] yields `Ok` for each whole entry; at the first damaged byte (or a
/// read error) it yields one error and then `None`. A file ending on an entry boundary ends
/// without error.
#[derive(Debug)]
pub struct Entries<'a> {
    reader: &'a LogReader,
    cursor: Cursor,
    next: usize,
    done: bool,
}

impl Entries<'_> {
    /// File offset of the next entry.
    pub fn offset(&self) -> usize {
        self.next
    }

    /// The next entry, or the error that ends the walk.
    #[allow(clippy::should_implement_trait)] // a lending iterator: entries borrow the walk
    pub fn next_entry(&mut self) -> Option<Result<LogEntry<'_>, LogError>> {
        if self.done {
            return None;
        }
        let at = self.next;
        match self.cursor.entry_at(self.reader.source(), at) {
            Ok(Some(entry)) => {
                self.next = entry.end_offset();
                Some(Ok(entry))
            }
            Ok(None) => {
                self.done = true;
                None
            }
            Err(e) => {
                self.done = true;
                Some(Err(LogError::from_cursor(&self.reader.path, at, e)))
            }
        }
    }

    /// Counts the remaining entries (for tests and tools); stops at the first error.
    pub fn count_whole(mut self) -> usize {
        let mut n = 0;
        while let Some(Ok(_)) = self.next_entry() {
            n += 1;
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::format::{encode_entry, MAX_ENTRY_PAYLOAD};
    use crate::time::TimeVal;

    fn sample() -> Vec<u8> {
        let mut file = Cookie::ours(0).to_bytes().to_vec();
        let mut buf = [0u8; 64];
        for i in 0..4 {
            let n = encode_entry(&mut buf, 4, 1, TimeVal::new(100, i), &[i as u8; 10]).unwrap();
            file.extend_from_slice(&buf[..n]);
        }
        file
    }

    /// Every entry (or the error) of a walk, owned.
    fn all(r: &LogReader) -> Vec<Result<(usize, Vec<u8>), String>> {
        let mut out = Vec::new();
        let mut it = r.entries();
        while let Some(e) = it.next_entry() {
            out.push(
                e.map(|e| (e.offset, e.payload.to_vec()))
                    .map_err(|e| e.to_string()),
            );
        }
        out
    }

    fn temp(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("vrpn-reader-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    #[test]
    fn cookie_rules() {
        assert!(check_log_cookie(b"vrpn: ver. 07.38  0\0\0\0\0\0").is_ok());
        assert!(check_log_cookie(b"vrpn: ver. 07.35  3\0\0\0\0\0").is_ok());
        assert!(check_log_cookie(b"vrpn: ver. 04.01  0\0\0\0\0\0").is_ok());
        assert!(check_log_cookie(b"vrpn: ver. 03.99  0\0\0\0\0\0").is_err());
        assert!(check_log_cookie(b"vrpn: ver. 08.00  0\0\0\0\0\0").is_err());
        assert!(check_log_cookie(b"GIF89a..................").is_err());
        assert_eq!(
            check_log_cookie(b"vrpn: ver."),
            Err(CookieProblem::Truncated { available: 10 })
        );
    }

    #[test]
    fn reads_entries_and_reports_truncation() {
        let file = sample();
        let r = LogReader::from_bytes(file.clone(), "mem.vrpn").unwrap();
        assert_eq!(r.cookie().version(), "07.38");
        let e = all(&r);
        assert_eq!(e.len(), 4);
        assert_eq!(e[1].as_ref().unwrap().0, 24 + 34);
        assert_eq!(e[3].as_ref().unwrap().1, [3u8; 10]);
        let mut it = r.entries_from(e[2].as_ref().unwrap().0);
        assert_eq!(it.next_entry().unwrap().unwrap().payload, [2u8; 10]);

        let cut = LogReader::from_bytes(file[..file.len() - 30].to_vec(), "cut.vrpn").unwrap();
        let e = all(&cut);
        assert_eq!(e.len(), 4);
        assert!(e[..3].iter().all(Result::is_ok));
        assert_eq!(
            e[3],
            Err("cut.vrpn: byte 126: file ends inside an entry header (4 of 24 bytes)".into())
        );
    }

    #[test]
    fn corrupt_length_is_an_error() {
        let mut file = sample();
        file[24 + 34 + 16] = 0x40;
        let r = LogReader::from_bytes(file, "bad.vrpn").unwrap();
        let mut it = r.entries();
        assert!(it.next_entry().unwrap().is_ok());
        match it.next_entry().unwrap() {
            Err(LogError::BadEntry {
                offset, problem, ..
            }) => {
                assert_eq!(offset, 58);
                assert_eq!(problem, EntryProblem::LengthTooLong(0x4000_000a));
            }
            other => panic!("unexpected {other:?}"),
        }
        assert!(it.next_entry().is_none());
    }

    #[test]
    fn open_reports_missing_file_and_bad_cookie() {
        let err = LogReader::open("/nonexistent/dir/x.vrpn").unwrap_err();
        assert!(matches!(err, LogError::Open { .. }));
        assert_eq!(
            err.to_string(),
            "cannot read log file /nonexistent/dir/x.vrpn: no such file"
        );
        let err = LogReader::from_bytes(b"hello".to_vec(), "h").unwrap_err();
        assert!(matches!(
            err,
            LogError::BadCookie {
                problem: CookieProblem::Truncated { available: 5 },
                ..
            }
        ));
        let zeros = temp("zeros.vrpn", &[0u8; 4096]);
        let err = LogReader::open(&zeros).unwrap_err();
        assert!(matches!(err, LogError::BadCookie { .. }), "{err}");
    }

    /// A file read through the window gives exactly what the same bytes in memory give, for
    /// entries of every size around the window's edges, and a cut anywhere.
    #[test]
    fn a_file_walks_like_its_image_in_memory() {
        let mut file = Cookie::ours(0).to_bytes().to_vec();
        let mut buf = vec![0u8; crate::log::format::entry_len(MAX_ENTRY_PAYLOAD)];
        let mut i = 0u32;
        while file.len() < 3 * super::super::cursor::WINDOW_LEN {
            let len = [0, 1, 7, 1000, MAX_ENTRY_PAYLOAD, 20_000][i as usize % 6];
            let payload: Vec<u8> = (0..len).map(|k| (k as u32 ^ i) as u8).collect();
            let n = encode_entry(&mut buf, i as i32, 1, TimeVal::new(5, 0), &payload).unwrap();
            file.extend_from_slice(&buf[..n]);
            i += 1;
        }
        for cut in [file.len(), file.len() - 1, file.len() - 70_000, 300_000] {
            let bytes = &file[..cut];
            let on_disk = LogReader::open(temp("walk.vrpn", bytes)).unwrap();
            let in_memory = LogReader::from_bytes(bytes.to_vec(), on_disk.path()).unwrap();
            assert_eq!(on_disk.len(), cut as u64);
            let (a, b) = (all(&on_disk), all(&in_memory));
            assert_eq!(a.len(), b.len(), "cut at {cut}");
            assert!(a == b, "cut at {cut}");
        }
    }

    #[test]
    fn only_regular_files_are_opened_and_never_block() {
        let dir = std::env::temp_dir().join(format!("vrpn-reader-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("fifo.vrpn");
        let _ = std::fs::remove_file(&fifo);
        nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::S_IRWXU).unwrap();
        for (path, kind) in [
            (fifo.as_path(), "a FIFO"),
            (Path::new("/dev/zero"), "a character device"),
            (dir.as_path(), "a directory"),
        ] {
            let start = std::time::Instant::now();
            let err = LogReader::open(path).unwrap_err();
            assert!(start.elapsed() < std::time::Duration::from_secs(1));
            assert!(
                matches!(err, LogError::NotARegularFile { kind: k, .. } if k == kind),
                "{err}"
            );
            assert_eq!(
                err.to_string(),
                format!(
                    "{}: byte 0: {kind}, not a regular file (logs are read from regular files \
                     only)",
                    path.display()
                )
            );
        }
        std::fs::remove_file(&fifo).unwrap();
    }
}
