//! Inspection tools over a log file, the library half of the `vrpn_log` program: a walk that
//! resolves names and decodes payloads ([`Walk`], [`Record`], [`Decoded`]), a whole-file
//! [`Summary`], one-line text and (with the `json` feature) JSON renderings of an entry, and CSV
//! export of one device's reports ([`CsvKind`], [`plan_csv`], [`write_csv`]).
//!
//! Names are resolved the way a replaying reader resolves them: through the
//! descriptions met so far in the file, in file order, with a DISCONNECT entry clearing them.
//! Every function stops at the first damaged entry and hands back the [`LogError`](crate::log::LogError) (file, offset,
//! problem) alongside what it made of the whole entries before it.
//!
//! ```no_run
//! use vrpn::log::{LogReader, tools::Summary};
//!
//! let log = LogReader::open("server.vrpn")?;
//! let summary = Summary::compute(&log);
//! print!("{summary}");
//! println!("{:?} poses", summary.count("Tracker0", "vrpn_Tracker Pos_Quat"));
//! # Ok::<(), vrpn::log::LogError>(())
//! ```

mod csv;
mod decode;
#[cfg(feature = "json")]
mod json;
mod summary;
#[cfg(test)]
mod test_log;
mod text;
mod walk;

pub use csv::{csv_row, plan_csv, write_csv, CsvError, CsvKind, CsvPlan};
pub use decode::{system_type_name, Decoded, Field, TEXT_HEX_LIMIT};
#[cfg(feature = "json")]
pub use json::format_json;
pub use summary::{DeviceStats, Summary, SystemCounts, TypeStats};
pub use text::format_text;
pub use walk::{Record, Walk};
