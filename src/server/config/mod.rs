//! Parsers for `vrpn.cfg` (the generic server's device list) and `vrpn_Tracker.cfg` (the
//! per-tracker transform file). Pure functions: text in, typed values or a [`ConfigError`] out.
//!
//! Each entry is parsed by the driver that serves its keyword (found in
//! [`crate::drivers::REGISTRY`]) into the driver's own configuration type, a [`DeviceSpec`];
//! the line mechanics every parser shares (tokens, fields, errors) are in [`crate::config`].
//!
//! # `vrpn.cfg` rules (as C++ `vrpn_server` 07.35 applies them)
//!
//! * The file is read line by line. A line of [`MAX_LINE_LEN`] + 1 bytes or more (newline
//!   included) is an error, as in C++ (511 bytes with C++'s 512-byte buffer).
//! * A line shorter than 3 bytes (newline included) is ignored, and so is a line whose first
//!   character other than space or tab is `#`. There is no end-of-line comment: a `#` after the
//!   keyword is an ordinary token, harmless where it comes after the last field an entry reads,
//!   because extra tokens after the required ones are ignored.
//! * The keyword is the first token delimited by spaces and tabs **only**, matched exactly
//!   (case-sensitive). So a keyword alone on its line does not match in C++ (the newline is part
//!   of the token); we report that case as "expected N arguments, found 0", which is the same
//!   outcome (the entry fails) with a clearer message. A line holding only spaces or tabs (3 or
//!   more bytes) is, in C++, an unknown device with an empty name: we keep that (it becomes a
//!   [`UnknownDevice`] entry with an empty keyword, whose [`DeviceEntry::unknown_error`]
//!   says to make the line truly empty).
//! * Arguments are the tokens after the keyword, separated by C `isspace` characters (space,
//!   tab, newline, CR, vertical tab, form feed), so CRLF files work for ordinary entries.
//! * No general line continuation. Multi-line entries have their own rules: AnalogFly blocks
//!   end at a truly empty line, ButtonFly blocks at a line `end`, Fastrak and InterSense entries
//!   continue while a line ends in `\` (reset commands) or `/` (station devices). Lines read as
//!   part of a block bypass the comment and short-line filtering.
//! * Unknown keywords become [`UnknownDevice`] entries; the caller decides, like C++
//!   `vrpn_server`, whether to stop (the default, "bail") or warn and skip (`-warn`). See
//!   [`DeviceEntry::unknown_error`].
//!
//! # Where we are stricter than C++ (decisions)
//!
//! C++ reads fields with `sscanf`, which silently accepts number prefixes ("2.5" as an int
//! reads 2 and leaves ".5" for the next field; "60Hz" reads 60) and many absurd values. A lab
//! server must not start half-right, so:
//!
//! * every numeric token must be a complete number of the right kind, and finite;
//! * counts and indexes are range-checked (see each device's docs) instead of clamped;
//! * rates of the example devices must be greater than 0 (C++ accepts 0 and then never reports),
//!   and every rate must be at least 1e-9 per second and every period at most 10^9 s
//!   ([`crate::time::MAX_PERIOD`], about 31.7 years): beyond, C++ computes a schedule that
//!   overflows, and an earlier version of this server panicked;
//! * serial baud rates must be one of [`BAUD_RATES`] (C++ would parse, then fail to open);
//! * device names must be at most [`crate::wire::MAX_NAME_LEN`] bytes and contain no `@`;
//! * references to other devices must be `*name` (this server) or `name@host` (another one);
//! * a driver's own fields are checked as its folder documents.
//!
//! [`parse_str`] stops at the first error, like C++ `vrpn_server` without `-warn` (which
//! prints the problem, destroys the devices made so far and exits). [`parse_str_lenient`]
//! behaves like `-warn`: a bad entry is reported and skipped and parsing resumes at the next
//! unread line (lines a block already consumed are lost, unconsumed block lines are read as
//! top-level lines, exactly as C++ does).
//!
//! # One name, several interfaces
//!
//! A client opens one remote per interface (`TrackerRemote`, `ButtonRemote`, …) on the same
//! `NAME@host`, so one name may carry several interfaces, whether one device serves them all (a
//! Magellan is an Analog and a Button) or several entries share the name ("factoring":
//! `vrpn_Tracker_NULL Dev0 1 20.0` and `vrpn_Button_Example Dev0 2 4.0` make `Dev0` a tracker
//! and a button). Each entry says what it serves ([`DeviceSpec::served`]); a sub-device (a
//! tracker's wand) serves its own interfaces under its own name.
//!
//! Two devices serving the **same** interface under one name are allowed too, as in C++, which
//! does not check names: both are built and their reports interleave under one sender, which
//! a client cannot tell apart. [`name_clashes`] finds such pairs so that the server can warn,
//! naming both lines; nothing is skipped.
//!
//! # Our extensions
//!
//! `vrpn_Analog_Example` and `vrpn_Text_Example` are not part of C++ VRPN; a C++
//! `vrpn_server` reports them as unknown devices.

mod entry;
mod parse;
mod tracker_cfg;

pub use crate::config::lines::{c_tokens, classify_line, is_c_space, EntryTokens, LineClass};
pub use crate::config::{
    ConfigError, ConfigErrorKind, DeviceRef, SourceLocation, BAUD_RATES, LINESIZE, MAX_BUTTONS,
    MAX_CHANNELS, MAX_DIALS, MAX_LINE_LEN, MAX_TRACKER_SENSORS,
};
pub use crate::driver::registry::{DeviceSpec, Interface, Served};
pub use entry::{known_keywords, name_clashes, DeviceEntry, NameClash, ParseReport, UnknownDevice};
pub use parse::{parse_file, parse_file_lenient, parse_str, parse_str_lenient, read_config_text};
pub use tracker_cfg::{
    load_tracker_cfg, parse_tracker_cfg, RigidTransform, SensorTransform, TrackerTransforms,
    TRACKER_CFG_FILE,
};

/// The one entry of `text` as its driver's configuration type `T` (for tests and tools).
///
/// # Panics
///
/// When `text` does not parse, or its first entry is not a `T`.
#[cfg(any(test, feature = "sim"))]
pub fn parse_one<T: DeviceSpec + Clone>(text: &str) -> T {
    let entries = parse_str(text, "test.cfg").unwrap_or_else(|e| panic!("{e}"));
    match entries.first().and_then(|e| e.spec::<T>()) {
        Some(t) => t.clone(),
        None => panic!(
            "the first entry of {text:?} is not a {}",
            std::any::type_name::<T>()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_keywords_are_distinct() {
        let all: Vec<&str> = known_keywords().collect();
        for (i, k) in all.iter().enumerate() {
            assert!(!all[..i].contains(k), "{k} twice");
        }
    }
}
