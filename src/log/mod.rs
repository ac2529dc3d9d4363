//! VRPN log files (`.vrpn` stream files): the entry codec, a reader, a buffered
//! writer, and the name tables a reader rebuilds from the descriptions in a log.
//!
//! A file is the 24-byte cookie followed by entries, each a 24-byte header of six big-endian
//! words (type, sender, seconds, microseconds, payload length, zero) and the unpadded payload.
//! This module does no networking and no replay pacing; it turns files into [`LogEntry`] views
//! and messages into bytes identical to what C++ VRPN writes.
//!
//! ```no_run
//! use vrpn::log::{LogReader, NameTable};
//!
//! let log = LogReader::open("server.vrpn")?;
//! let mut names = NameTable::new();
//! let mut entries = log.entries();
//! while let Some(entry) = entries.next_entry() {
//!     let entry = entry?;
//!     names.observe(&entry).ok();
//!     if !entry.is_system() {
//!         println!("{} {:?} from {:?}", entry.time(),
//!                  names.type_name(entry.type_id()), names.sender_name(entry.sender()));
//!     }
//! }
//! # Ok::<(), vrpn::log::LogError>(())
//! ```

mod cursor;
// The entry codec; what a user needs of it is re-exported here.
pub mod folder;
#[doc(hidden)]
pub mod format;
pub mod names;
pub mod reader;
pub mod replay;
pub mod tools;
pub mod writer;

pub use folder::{FolderError, LogFolder, Refusal};
pub use format::{
    decode_entry, encode_entry, entry_len, EntryFault, EntryHeader, EntryProblem, EntryWalker,
    LogEntry, SystemEntry, ENTRY_HEADER_LEN, MAX_ENTRY_PAYLOAD,
};
pub use names::{NameEvent, NameTable};
pub use reader::{check_log_cookie, CookieProblem, Entries, LogError, LogReader};
pub use writer::{log_cookie_from_peer, LogWriter, DEFAULT_BUFFER_LEN, MIN_BUFFER_LEN};

/// Creates a new log file at `path` (never overwriting one) with this crate's cookie, as the
/// byte sink a connection's session writes to.
pub(crate) fn open_sink(path: &str) -> Result<LogWriter<Box<dyn std::io::Write>>, LogError> {
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .map_err(|error| LogError::Create {
            path: path.into(),
            error,
        })?;
    Ok(sink_from_file(file, std::path::Path::new(path)))
}

/// A byte sink over a log file already created (empty) at `path`, with this crate's cookie.
pub(crate) fn sink_from_file(
    file: std::fs::File,
    path: &std::path::Path,
) -> LogWriter<Box<dyn std::io::Write>> {
    let cookie = crate::wire::Cookie::ours(0).to_bytes();
    LogWriter::new(
        Box::new(file) as Box<dyn std::io::Write>,
        path,
        &cookie,
        DEFAULT_BUFFER_LEN,
    )
}
