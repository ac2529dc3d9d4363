//! The mechanics of `vrpn.cfg` lines, shared by every driver's parser and by the server's file
//! reader: where a problem is ([`ConfigError`], always `FILE:LINE: KEYWORD: problem`), the
//! tokenizer with C++ `vrpn_server`'s rules ([`lines`]), the field parsers ([`fields`]: counts,
//! numbers, rates, baud rates, names, references to other devices), and [`ConfigLine`], the
//! entry a driver's parser is handed.
//!
//! This module sits below the drivers and the server: a driver parses its own lines with it,
//! and the server ([`crate::server::config`]) reads files, finds each entry's driver in the
//! registry ([`crate::driver::registry`]) and hands it the line.
//!
//! # Where we are stricter than C++ (decisions every parser follows)
//!
//! C++ reads fields with `sscanf`, which silently accepts number prefixes ("2.5" as an int
//! reads 2 and leaves ".5" for the next field; "60Hz" reads 60) and many absurd values. A lab
//! server must not start half-right, so:
//!
//! * every numeric token must be a complete number of the right kind, and finite;
//! * counts and indexes are range-checked instead of clamped;
//! * serial baud rates must be one of [`BAUD_RATES`] (C++ would parse, then fail to open);
//! * device names must be at most [`crate::wire::MAX_NAME_LEN`] bytes and contain no `@`;
//! * references to other devices must be `*name` (this server) or `name@host` (another one).

pub mod continuation;
mod device_ref;
mod error;
pub mod fields;
mod line;
pub mod lines;

pub use device_ref::{DeviceRef, DeviceRefError};
pub use error::{ConfigError, ConfigErrorKind, Ctx, SourceLocation};
pub use line::ConfigLine;
pub use lines::RawLine;

/// Size of the line buffer C++ `vrpn_server` reads `vrpn.cfg` with (`LINESIZE`).
pub const LINESIZE: usize = 512;

/// Longest accepted line in bytes, newline included (C++ rejects `strlen >= LINESIZE - 1`).
pub const MAX_LINE_LEN: usize = LINESIZE - 2;

/// Baud rates a serial port can be opened with: the standard rates from 300 to 115200.
pub const BAUD_RATES: [u32; 9] = [300, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200];

/// Most sensors we accept for trackers whose count C++ does not bound (NULL, Spin, and
/// `vrpn_Tracker.cfg` entries). A guard against typos and absurd allocations.
pub const MAX_TRACKER_SENSORS: u32 = 1024;

/// Most buttons on one device (`vrpn_BUTTON_MAX_BUTTONS`).
pub const MAX_BUTTONS: u32 = 256;

/// Most analog channels on one device (`vrpn_CHANNEL_MAX`).
pub const MAX_CHANNELS: u32 = 128;

/// Most dials on one device (`vrpn_DIAL_MAX`).
pub const MAX_DIALS: u32 = 128;
