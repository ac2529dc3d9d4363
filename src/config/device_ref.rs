//! References from one device to another (`*NAME` on this server, `NAME@host` on another), as
//! layered devices and filters name the device they read.

use std::fmt;

/// A reference from a layered device to the device it reads.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum DeviceRef {
    /// `*NAME`: a device served by this same server (the `*` is not stored).
    Local(String),
    /// `NAME@host[:port]`: a device on another server, stored whole.
    Remote(String),
}

/// Why a token is not a device reference.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceRefError {
    /// `*` alone.
    NothingAfterStar,
    /// `*NAME@host`.
    StarAndAt,
    /// `@host` or `NAME@`.
    EmptySide,
    /// A bare name (the token is kept to suggest both forms).
    Bare(String),
}

impl fmt::Display for DeviceRefError {
    /// The problem, written to follow the token (`'M0' must be *M0 or M0@host`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DeviceRefError::NothingAfterStar => {
                f.write_str("has nothing after the '*'; write *NAME")
            }
            DeviceRefError::StarAndAt => {
                f.write_str("mixes '*' (this server) with '@' (another server)")
            }
            DeviceRefError::EmptySide => {
                f.write_str("must have a device name before and a host after the '@'")
            }
            DeviceRefError::Bare(tok) => write!(
                f,
                "must be *{tok} (a device of this server) or {tok}@host (a device on another \
                 server)"
            ),
        }
    }
}

impl std::error::Error for DeviceRefError {}

impl DeviceRef {
    /// Parses `*NAME` or `NAME@host`.
    pub fn parse(tok: &str) -> Result<DeviceRef, DeviceRefError> {
        if let Some(name) = tok.strip_prefix('*') {
            if name.is_empty() {
                return Err(DeviceRefError::NothingAfterStar);
            }
            if name.contains('@') {
                return Err(DeviceRefError::StarAndAt);
            }
            return Ok(DeviceRef::Local(name.to_owned()));
        }
        match tok.split_once('@') {
            Some((dev, host)) if !dev.is_empty() && !host.is_empty() => {
                Ok(DeviceRef::Remote(tok.to_owned()))
            }
            Some(_) => Err(DeviceRefError::EmptySide),
            None => Err(DeviceRefError::Bare(tok.to_owned())),
        }
    }

    /// The name to open a remote with: the local name without `*`, or the full remote name.
    pub fn name(&self) -> &str {
        match self {
            DeviceRef::Local(n) | DeviceRef::Remote(n) => n,
        }
    }

    /// Whether the device is served by this same server.
    pub fn is_local(&self) -> bool {
        matches!(self, DeviceRef::Local(_))
    }
}

impl fmt::Display for DeviceRef {
    /// Writes the reference as it appears in `vrpn.cfg`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DeviceRef::Local(n) => write!(f, "*{n}"),
            DeviceRef::Remote(n) => f.write_str(n),
        }
    }
}
