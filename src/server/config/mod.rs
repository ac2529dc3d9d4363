//! Parsers for `vrpn.cfg` (the generic server's device list) and `vrpn_Tracker.cfg` (the
//! per-tracker transform file). Pure functions: text in, typed values or a [`ConfigError`] out.
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
//!   [`DeviceConfig::Unknown`] entry with an empty keyword, whose [`DeviceEntry::unknown_error`]
//!   says to make the line truly empty).
//! * Arguments are the tokens after the keyword, separated by C `isspace` characters (space,
//!   tab, newline, CR, vertical tab, form feed), so CRLF files work for ordinary entries.
//! * No general line continuation. Multi-line entries have their own rules: AnalogFly blocks
//!   end at a truly empty line, ButtonFly blocks at a line `end`, Fastrak and InterSense entries
//!   continue while a line ends in `\` (reset commands) or `/` (station devices). Lines read as
//!   part of a block bypass the comment and short-line filtering.
//! * Unknown keywords become [`DeviceConfig::Unknown`] entries; the caller decides, like C++
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
//! * the Fastrak `*N` reset pause must be a whole number of seconds.
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
//! and a button). Each entry says what it serves ([`DeviceConfig::served`]); a Fastrak or
//! InterSense station device serves its own interfaces under its own name.
//!
//! Two devices serving the **same** interface under one name are allowed too, as in C++, which
//! does not check names: both are built and their reports interleave under one sender, which
//! a client cannot tell apart. [`name_clashes`] finds such pairs so that the server can warn,
//! naming both lines; nothing is skipped.
//!
//! # Our extensions
//!
//! `vrpn_Analog_Example` ([`AnalogExample`]) and `vrpn_Text_Example` ([`TextExample`]) are not
//! part of C++ VRPN; a C++ `vrpn_server` reports them as unknown devices.

mod devices;
mod entry;
mod error;
mod fastrak;
mod fields;
mod fly;
mod lines;
mod parse;
mod tracker_cfg;

pub use devices::{
    AnalogExample, ButtonExample, CerealBox, DialExample, Dyna, Flock, FlockParallel, Hemisphere,
    Joylin, Magellan, TextExample, TrackerNull, TrackerSpin,
};
pub use entry::{
    name_clashes, DeviceConfig, DeviceEntry, Interface, NameClash, ParseReport, Served,
};
pub use error::{ConfigError, ConfigErrorKind, SourceLocation};
pub use fastrak::{Fastrak, InterSense, InterSensePort, ResetStep, StationDevice, WandClip};
pub use fly::{
    AnalogFly, AnalogFlyAxis, Axis, ButtonFly, ButtonFlyAxis, ButtonRef, DeviceRef, FlyMode,
    ScaleAnalog,
};
pub use lines::{c_tokens, classify_line, is_c_space, EntryTokens, LineClass};
pub use parse::{parse_file, parse_file_lenient, parse_str, parse_str_lenient, read_config_text};
pub use tracker_cfg::{
    load_tracker_cfg, parse_tracker_cfg, RigidTransform, SensorTransform, TrackerTransforms,
    TRACKER_CFG_FILE,
};

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

/// Most receivers on an Ascension Flock of Birds.
pub const MAX_FLOCK_SENSORS: u32 = 13;

/// Most axis lines in one ButtonFly block.
pub const MAX_BUTTONFLY_AXES: usize = 200;

/// Longest device name in a ButtonFly axis line.
pub const MAX_BUTTONFLY_NAME: usize = 199;

/// Longest combined Fastrak/InterSense reset-command string, in bytes.
pub const MAX_RESET_COMMANDS: usize = 2048;

/// Every keyword this parser recognises, C++ ones first, then our extensions.
pub const KNOWN_KEYWORDS: [&str; 16] = [
    kw::TRACKER_NULL,
    kw::TRACKER_SPIN,
    kw::BUTTON_EXAMPLE,
    kw::DIAL_EXAMPLE,
    kw::ANALOG_FLY,
    kw::BUTTON_FLY,
    kw::JOYLIN,
    kw::FASTRAK,
    kw::INTERSENSE,
    kw::FLOCK,
    kw::FLOCK_PARALLEL,
    kw::MAGELLAN,
    kw::CEREALBOX,
    kw::DYNA,
    kw::ANALOG_EXAMPLE,
    kw::TEXT_EXAMPLE,
];

/// The keyword strings, spelled as in `vrpn.cfg`.
pub mod kw {
    /// [`super::TrackerNull`].
    pub const TRACKER_NULL: &str = "vrpn_Tracker_NULL";
    /// [`super::TrackerSpin`].
    pub const TRACKER_SPIN: &str = "vrpn_Tracker_Spin";
    /// [`super::ButtonExample`].
    pub const BUTTON_EXAMPLE: &str = "vrpn_Button_Example";
    /// [`super::DialExample`].
    pub const DIAL_EXAMPLE: &str = "vrpn_Dial_Example";
    /// [`super::AnalogFly`].
    pub const ANALOG_FLY: &str = "vrpn_Tracker_AnalogFly";
    /// [`super::ButtonFly`].
    pub const BUTTON_FLY: &str = "vrpn_Tracker_ButtonFly";
    /// [`super::Joylin`].
    pub const JOYLIN: &str = "vrpn_Joylin";
    /// [`super::Fastrak`].
    pub const FASTRAK: &str = "vrpn_Tracker_Fastrak";
    /// [`super::InterSense`].
    pub const INTERSENSE: &str = "vrpn_Tracker_InterSense";
    /// [`super::Flock`].
    pub const FLOCK: &str = "vrpn_Tracker_Flock";
    /// [`super::FlockParallel`].
    pub const FLOCK_PARALLEL: &str = "vrpn_Tracker_Flock_Parallel";
    /// [`super::Magellan`].
    pub const MAGELLAN: &str = "vrpn_Magellan";
    /// [`super::CerealBox`].
    pub const CEREALBOX: &str = "vrpn_CerealBox";
    /// [`super::Dyna`].
    pub const DYNA: &str = "vrpn_Tracker_Dyna";
    /// [`super::AnalogExample`] (our extension, not in C++ VRPN).
    pub const ANALOG_EXAMPLE: &str = "vrpn_Analog_Example";
    /// [`super::TextExample`] (our extension, not in C++ VRPN).
    pub const TEXT_EXAMPLE: &str = "vrpn_Text_Example";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_keywords_are_distinct() {
        for (i, k) in KNOWN_KEYWORDS.iter().enumerate() {
            assert!(!KNOWN_KEYWORDS[..i].contains(k), "{k} twice");
        }
    }
}
