//! Reading a log file: cookie check, then entries one by one as borrowed
//! views, stopping cleanly at the first damaged byte.

use std::path::{Path, PathBuf};

use super::format::{EntryFault, EntryProblem, EntryWalker, LogEntry};
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
            | LogError::PayloadTooLong { path, .. }
            | LogError::Open { path, .. }
            | LogError::Create { path, .. } => path,
        }
    }

    /// The byte offset concerned, where one applies.
    pub fn offset(&self) -> Option<usize> {
        match self {
            LogError::Io { offset, .. } | LogError::BadEntry { offset, .. } => Some(*offset),
            LogError::BadCookie { .. } => Some(0),
            LogError::PayloadTooLong { .. } | LogError::Open { .. } | LogError::Create { .. } => {
                None
            }
        }
    }

    pub(crate) fn from_fault(path: &Path, fault: EntryFault) -> LogError {
        LogError::BadEntry {
            path: path.to_owned(),
            offset: fault.offset,
            problem: fault.problem,
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

/// A log file held in memory (C++ preloads too), with its cookie checked.
///
/// [`LogReader::entries`] walks it without allocating per entry; several walks may run at once.
#[derive(Clone, Debug)]
pub struct LogReader {
    path: PathBuf,
    bytes: Vec<u8>,
    cookie: Cookie,
    cookie_bytes: [u8; COOKIE_LEN],
}

impl LogReader {
    /// Reads the whole file at `path` and checks its cookie.
    pub fn open(path: impl AsRef<Path>) -> Result<LogReader, LogError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|error| LogError::Open {
            path: path.to_owned(),
            error,
        })?;
        LogReader::from_bytes(bytes, path)
    }

    /// Takes a file image already in memory; `name` is used in error messages.
    pub fn from_bytes(bytes: Vec<u8>, name: impl Into<PathBuf>) -> Result<LogReader, LogError> {
        let path = name.into();
        match check_log_cookie(&bytes) {
            Ok(cookie) => {
                let mut cookie_bytes = [0u8; COOKIE_LEN];
                cookie_bytes.copy_from_slice(&bytes[..COOKIE_LEN]);
                Ok(LogReader {
                    path,
                    bytes,
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

    /// The whole file image.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Iterates over the entries from the first one.
    pub fn entries(&self) -> Entries<'_> {
        self.entries_from(COOKIE_LEN)
    }

    /// Iterates over the entries starting at file offset `offset`, which must be an entry
    /// boundary (e.g. a saved [`Entries::offset`]); an offset past the end yields nothing.
    pub fn entries_from(&self, offset: usize) -> Entries<'_> {
        let offset = offset.max(COOKIE_LEN).min(self.bytes.len());
        Entries {
            walker: EntryWalker::new(&self.bytes[offset..], offset),
            path: &self.path,
        }
    }
}

/// Entries of a [`LogReader`], in file order.
///
/// Yields `Ok` for each whole entry; at the first damaged byte yields one
/// [`LogError::BadEntry`] and then ends. A file ending on an entry boundary ends without error.
#[derive(Clone, Debug)]
pub struct Entries<'a> {
    walker: EntryWalker<'a>,
    path: &'a Path,
}

impl Entries<'_> {
    /// File offset of the next entry.
    pub fn offset(&self) -> usize {
        self.walker.offset()
    }
}

impl<'a> Iterator for Entries<'a> {
    type Item = Result<LogEntry<'a>, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.walker
            .next()
            .map(|r| r.map_err(|fault| LogError::from_fault(self.path, fault)))
    }
}

impl std::iter::FusedIterator for Entries<'_> {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::format::encode_entry;
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
        let e: Vec<_> = r.entries().map(|e| e.unwrap()).collect();
        assert_eq!(e.len(), 4);
        assert_eq!(e[1].offset, 24 + 34);
        assert_eq!(e[3].payload, &[3u8; 10]);
        let mut it = r.entries_from(e[2].offset);
        assert_eq!(it.next().unwrap().unwrap(), e[2]);

        let cut = LogReader::from_bytes(file[..file.len() - 30].to_vec(), "cut.vrpn").unwrap();
        let mut it = cut.entries();
        for _ in 0..3 {
            assert!(it.next().unwrap().is_ok());
        }
        let err = it.next().unwrap().unwrap_err();
        assert_eq!(err.offset(), Some(24 + 3 * 34));
        assert_eq!(
            err.to_string(),
            "cut.vrpn: byte 126: file ends inside an entry header (4 of 24 bytes)"
        );
        assert!(it.next().is_none());
    }

    #[test]
    fn corrupt_length_is_an_error() {
        let mut file = sample();
        file[24 + 34 + 16] = 0x40;
        let r = LogReader::from_bytes(file, "bad.vrpn").unwrap();
        let all: Vec<_> = r.entries().collect();
        assert_eq!(all.len(), 2);
        match &all[1] {
            Err(LogError::BadEntry {
                offset, problem, ..
            }) => {
                assert_eq!(*offset, 58);
                assert_eq!(*problem, EntryProblem::LengthTooLong(0x4000_000a));
            }
            other => panic!("unexpected {other:?}"),
        }
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
    }
}
