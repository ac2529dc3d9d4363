//! The crate's error type: each variant says what went wrong in words a user can act on.

use std::io;

use crate::name::NameError;
use crate::proto::names::NameLimit;

/// Errors returned by connection set-up and by calls that can fail.
#[derive(Debug)]
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
    /// A log file cannot be written or read (file, offset and problem in the text).
    Log(String),
    /// The operation needs a different kind of connection (e.g. a server socket on a client).
    Unsupported(&'static str),
}

impl Error {
    pub(crate) fn from_log(e: crate::log::LogError) -> Error {
        Error::Log(e.to_string())
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
            Error::Unsupported(what) => write!(f, "not supported: {what}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            Error::Name(e) => Some(e),
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
