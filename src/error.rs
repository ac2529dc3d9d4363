//! The crate's error type: each variant says what went wrong in words a user can act on.

use std::io;

use std::path::PathBuf;

use crate::log::LogError;
use crate::name::NameError;
use crate::proto::names::NameLimit;
use crate::proto::ConnectionState;

/// Errors returned by connection set-up and by calls that can fail.
///
/// New variants may be added: match with a `_` arm.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// The device name cannot be parsed.
    Name(NameError),
    /// The host name does not resolve to an IPv4 address.
    Resolve {
        /// Host as given.
        host: String,
        /// What the resolver said.
        reason: String,
    },
    /// A socket or file operation failed.
    Io {
        /// What we were doing.
        context: String,
        /// The OS error.
        source: io::Error,
    },
    /// A sender or type name cannot be registered.
    NameLimit(NameLimit),
    /// A message payload is larger than a VRPN peer accepts.
    PayloadTooLarge(usize),
    /// A log file cannot be written or read (file, offset and problem in the text); see
    /// also [`LogNotFound`](Self::LogNotFound) and [`LogDamaged`](Self::LogDamaged).
    Log(String),
    /// The log file to read does not exist.
    LogNotFound {
        /// The path as given.
        path: PathBuf,
    },
    /// The log file is not a VRPN log or is damaged (bad cookie, truncated or corrupt entry):
    /// the inner error names file, offset and problem.
    LogDamaged(LogError),
    /// A client sent before its connection was up (or while it reconnects): nothing was
    /// sent. The state it was in is given.
    NotConnected(ConnectionState),
    /// The operation needs a different kind of connection (e.g. a server socket on a client).
    Unsupported(&'static str),
    /// An argument is out of range for the device (an image region outside the image, a
    /// channel that does not exist, a name too long for its field): the text says which.
    InvalidArgument(String),
}

impl Error {
    /// A log error as the variant a user matches: not found, damaged, or other.
    pub(crate) fn from_log(e: LogError) -> Error {
        match e {
            LogError::Open { path, error } | LogError::Io { path, error, .. }
                if error.kind() == io::ErrorKind::NotFound =>
            {
                Error::LogNotFound { path }
            }
            e @ (LogError::BadCookie { .. } | LogError::BadEntry { .. }) => Error::LogDamaged(e),
            e => Error::Log(e.to_string()),
        }
    }

    pub(crate) fn io(context: impl Into<String>, source: io::Error) -> Error {
        Error::Io {
            context: context.into(),
            source,
        }
    }
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Name(e) => e.fmt(f),
            Error::Resolve { host, reason } => write!(
                f,
                "cannot resolve host {host:?} to an IPv4 address ({reason}); check the name \
                 after '@' or use a dotted-quad address"
            ),
            Error::Io { context, source } => write!(f, "{context}: {source}"),
            Error::NameLimit(e) => e.fmt(f),
            Error::PayloadTooLarge(n) => write!(
                f,
                "payload of {n} bytes exceeds the {} bytes a VRPN peer accepts",
                crate::wire::MAX_PAYLOAD
            ),
            Error::Log(text) => f.write_str(text),
            Error::LogNotFound { path } => {
                write!(f, "cannot read log file {}: no such file", path.display())
            }
            Error::LogDamaged(e) => e.fmt(f),
            Error::NotConnected(state) => write!(
                f,
                "not sent: the connection is not up yet ({state:?}); send once it is Connected"
            ),
            Error::Unsupported(what) => write!(f, "not supported: {what}"),
            Error::InvalidArgument(what) => write!(f, "invalid argument: {what}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            Error::Name(e) => Some(e),
            Error::LogDamaged(e) => Some(e),
            _ => None,
        }
    }
}

impl From<NameError> for Error {
    fn from(e: NameError) -> Self {
        Error::Name(e)
    }
}

impl From<NameLimit> for Error {
    fn from(e: NameLimit) -> Self {
        Error::NameLimit(e)
    }
}
