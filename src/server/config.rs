//! Parsers for `vrpn.cfg` (the generic server's device list) and `vrpn_Tracker.cfg` (the
//! per-tracker transform file). Pure functions: text in, typed values or a [`ConfigError`] out.
//!
//! # `vrpn.cfg` rules (as C++ `vrpn_server` 07.35 applies them, CONFIG.md §2)
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
//! * rates of the example devices must be greater than 0 (C++ accepts 0 and then never reports);
//! * serial baud rates must be one of [`BAUD_RATES`] (C++ would parse, then fail to open);
//! * device names must be at most [`crate::wire::MAX_NAME_LEN`] bytes and contain no `@`;
//! * two entries may not define the same device name (C++ lets them share one sender);
//! * references to other devices must be `*name` (this server) or `name@host` (another one);
//! * the Fastrak `*N` reset pause must be a whole number of seconds.
//!
//! [`parse_str`] stops at the first error, like C++ `vrpn_server` without `-warn` (which
//! prints the problem, destroys the devices made so far and exits). [`parse_str_lenient`]
//! behaves like `-warn`: a bad entry is reported and skipped and parsing resumes at the next
//! unread line (lines a block already consumed are lost, unconsumed block lines are read as
//! top-level lines, exactly as C++ does).
//!
//! # Our extensions
//!
//! `vrpn_Analog_Example` ([`AnalogExample`]) and `vrpn_Text_Example` ([`TextExample`]) are not
//! part of C++ VRPN; a C++ `vrpn_server` reports them as unknown devices.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use crate::wire::MAX_NAME_LEN;

/// Size of the line buffer C++ `vrpn_server` reads `vrpn.cfg` with (`LINESIZE`).
pub const LINESIZE: usize = 512;

/// Longest accepted line in bytes, newline included (C++ rejects `strlen >= LINESIZE - 1`).
pub const MAX_LINE_LEN: usize = LINESIZE - 2;

/// Baud rates a serial port can be opened with (CONFIG.md §2).
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

// ---------------------------------------------------------------------------------------------
// Locations and errors
// ---------------------------------------------------------------------------------------------

/// Where an entry or a problem is in a configuration file.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct SourceLocation {
    /// The file name as given to the parser (a path for [`parse_file`]).
    pub file: String,
    /// 1-based line number.
    pub line: usize,
}

impl fmt::Display for SourceLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.file, self.line)
    }
}

/// What kind of problem a [`ConfigError`] reports (the message has the details).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ConfigErrorKind {
    /// The file could not be read.
    Io,
    /// The file is not valid UTF-8.
    NotUtf8,
    /// A line is longer than [`MAX_LINE_LEN`].
    LineTooLong,
    /// An entry has fewer arguments than it needs.
    MissingArguments,
    /// A token that should be a number is not one.
    BadNumber,
    /// A number is outside the range the device accepts.
    OutOfRange,
    /// A word-valued field has a value the device does not know.
    BadValue,
    /// A device name (or a reference to another device) is malformed.
    BadName,
    /// Two entries define the same device name.
    DuplicateName,
    /// A multi-line entry is not closed before the end of the file.
    UnclosedBlock,
    /// A line inside a multi-line entry is malformed.
    BadBlockLine,
    /// The keyword is not one we know (see [`DeviceEntry::unknown_error`]).
    UnknownDevice,
    /// `vrpn_Tracker.cfg` has no entry for the requested tracker.
    TrackerNotFound,
}

/// A configuration problem, always naming the file and (except for unreadable files) the line.
///
/// Displays as `FILE:LINE: MESSAGE`, e.g.
/// `vrpn.cfg:12: vrpn_Tracker_NULL: expected 3 arguments (name, sensors, rate), found 2`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigError {
    kind: ConfigErrorKind,
    file: String,
    line: Option<usize>,
    message: String,
}

impl ConfigError {
    /// An error at one line of a file.
    pub fn at_line(kind: ConfigErrorKind, file: &str, line: usize, message: String) -> Self {
        ConfigError {
            kind,
            file: file.to_owned(),
            line: Some(line),
            message,
        }
    }

    /// An error about a whole file (it could not be read).
    pub fn whole_file(kind: ConfigErrorKind, file: &str, message: String) -> Self {
        ConfigError {
            kind,
            file: file.to_owned(),
            line: None,
            message,
        }
    }

    /// The kind of problem.
    pub fn kind(&self) -> ConfigErrorKind {
        self.kind
    }

    /// The file name, as given to the parser.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The 1-based line, or `None` when the file itself could not be read.
    pub fn line(&self) -> Option<usize> {
        self.line
    }

    /// The problem in words, without the `FILE:LINE: ` prefix.
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.file, line, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for ConfigError {}

/// Error context: file, line and what is being parsed (e.g. `vrpn_Tracker_NULL`).
struct Ctx<'a> {
    file: &'a str,
    line: usize,
    what: String,
}

impl<'a> Ctx<'a> {
    fn new(file: &'a str, line: usize, what: impl Into<String>) -> Self {
        Ctx {
            file,
            line,
            what: what.into(),
        }
    }

    /// The same context at another line (inside a block).
    fn at(&self, line: usize) -> Ctx<'a> {
        Ctx::new(self.file, line, self.what.clone())
    }

    fn err(&self, kind: ConfigErrorKind, message: impl fmt::Display) -> ConfigError {
        ConfigError::at_line(
            kind,
            self.file,
            self.line,
            format!("{}: {message}", self.what),
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Tokenizer
// ---------------------------------------------------------------------------------------------

/// C `isspace` in the "C" locale: space, tab, newline, vertical tab, form feed, carriage return.
pub fn is_c_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\n' | '\x0b' | '\x0c' | '\r')
}

/// Splits `text` into `isspace`-separated tokens, as successive `sscanf("%s")` reads do.
pub fn c_tokens(text: &str) -> Vec<&str> {
    text.split(is_c_space).filter(|t| !t.is_empty()).collect()
}

/// What the top-level reader makes of one line of `vrpn.cfg`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LineClass<'a> {
    /// Shorter than 3 bytes, newline included: ignored.
    Short,
    /// First character other than space or tab is `#`: ignored.
    Comment,
    /// Anything else: an entry (possibly of an unknown type).
    Entry(EntryTokens<'a>),
}

/// The tokens of an entry's first line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EntryTokens<'a> {
    /// The first `isspace`-delimited token (what C++ prints for an unknown device). Empty for a
    /// line of only blanks.
    pub keyword: &'a str,
    /// Whether C++ would match `keyword` against its table: its keyword token is delimited by
    /// spaces and tabs only, so it fails when anything but a space or tab (usually the newline
    /// of a keyword alone on its line) follows the keyword.
    pub matchable: bool,
    /// The text after `keyword`, up to and including the newline.
    pub rest: &'a str,
    /// The `isspace`-separated tokens of `rest`.
    pub args: Vec<&'a str>,
}

/// Classifies one raw line (newline included, if any) with C++ `vrpn_server`'s rules.
pub fn classify_line(line: &str) -> LineClass<'_> {
    if line.len() < 3 {
        return LineClass::Short;
    }
    let after_blanks = line.trim_start_matches([' ', '\t']);
    if after_blanks.starts_with('#') {
        return LineClass::Comment;
    }
    // C++: strtok(line, " \t") is compared with the keyword.
    let strtok_token = after_blanks
        .split([' ', '\t'])
        .next()
        .unwrap_or(after_blanks);
    // C++: sscanf("%s") names an unknown device and reads the fields.
    let start = line.trim_start_matches(is_c_space);
    let kw_end = start.find(is_c_space).unwrap_or(start.len());
    let keyword = &start[..kw_end];
    let rest = &start[kw_end..];
    LineClass::Entry(EntryTokens {
        keyword,
        matchable: !keyword.is_empty() && strtok_token == keyword,
        rest,
        args: c_tokens(rest),
    })
}

/// One physical line: its number and text (newline included, if the file had one).
#[derive(Clone, Copy, Debug)]
struct RawLine<'a> {
    number: usize,
    text: &'a str,
}

impl<'a> RawLine<'a> {
    /// The text without its newline.
    fn content(&self) -> &'a str {
        self.text.strip_suffix('\n').unwrap_or(self.text)
    }
}

/// Reads physical lines, enforcing the line-length limit.
struct Reader<'a> {
    file: &'a str,
    lines: std::iter::Enumerate<std::str::SplitInclusive<'a, char>>,
    last_number: usize,
}

impl<'a> Reader<'a> {
    fn new(text: &'a str, file: &'a str) -> Self {
        Reader {
            file,
            lines: text.split_inclusive('\n').enumerate(),
            last_number: 0,
        }
    }

    fn next_raw(&mut self) -> Option<Result<RawLine<'a>, ConfigError>> {
        let (index, text) = self.lines.next()?;
        let number = index + 1;
        self.last_number = number;
        if text.len() > MAX_LINE_LEN {
            return Some(Err(ConfigError::at_line(
                ConfigErrorKind::LineTooLong,
                self.file,
                number,
                format!(
                    "line is {} characters long; lines must be at most {MAX_LINE_LEN} \
                     characters including the newline (the C++ limit); shorten it",
                    text.len()
                ),
            )));
        }
        Some(Ok(RawLine { number, text }))
    }

    /// The next line of a block started at `ctx`; the end of the file is an error that says
    /// what was expected (`closing`).
    fn block_line(&mut self, ctx: &Ctx<'_>, closing: &str) -> Result<RawLine<'a>, ConfigError> {
        match self.next_raw() {
            Some(line) => line,
            None => Err(ctx.err(
                ConfigErrorKind::UnclosedBlock,
                format!(
                    "the file ends (after line {}) before {closing}",
                    self.last_number
                ),
            )),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Field parsers
// ---------------------------------------------------------------------------------------------

/// Fails unless `args` has at least `min` tokens; `usage` names them.
fn need(ctx: &Ctx<'_>, args: &[&str], min: usize, usage: &str) -> Result<(), ConfigError> {
    if args.len() >= min {
        return Ok(());
    }
    let plural = if min == 1 { "" } else { "s" };
    Err(ctx.err(
        ConfigErrorKind::MissingArguments,
        format!(
            "expected {min} argument{plural} ({usage}), found {}",
            args.len()
        ),
    ))
}

/// A whole number in `lo..=hi`.
fn int_in(ctx: &Ctx<'_>, field: &str, tok: &str, lo: i64, hi: i64) -> Result<i64, ConfigError> {
    use std::num::IntErrorKind;
    let range = || {
        ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be between {lo} and {hi}, found {tok}"),
        )
    };
    match tok.parse::<i64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        Ok(_) => Err(range()),
        Err(e)
            if matches!(
                e.kind(),
                IntErrorKind::PosOverflow | IntErrorKind::NegOverflow
            ) =>
        {
            Err(range())
        }
        Err(_) => Err(ctx.err(
            ConfigErrorKind::BadNumber,
            format!("{field} must be a whole number, found '{tok}'"),
        )),
    }
}

/// A whole number in `lo..=hi`, as `u32` (callers pass non-negative bounds).
fn uint_in(ctx: &Ctx<'_>, field: &str, tok: &str, lo: u32, hi: u32) -> Result<u32, ConfigError> {
    let v = int_in(ctx, field, tok, i64::from(lo), i64::from(hi))?;
    u32::try_from(v).map_err(|_| {
        ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be between {lo} and {hi}, found {tok}"),
        )
    })
}

/// Any whole number that fits a C `int`.
fn any_int(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<i32, ConfigError> {
    let v = int_in(ctx, field, tok, i64::from(i32::MIN), i64::from(i32::MAX))?;
    Ok(i32::try_from(v).unwrap_or_default())
}

/// A finite number read as C++ reads `%f`/`%g`: the nearest `f32`.
fn f32_field(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    match tok.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be a finite number, found '{tok}'"),
        )),
        Err(_) => Err(ctx.err(
            ConfigErrorKind::BadNumber,
            format!("{field} must be a number, found '{tok}'"),
        )),
    }
}

/// A finite number read as C++ reads `%lf`.
fn f64_field(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f64, ConfigError> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be a finite number, found '{tok}'"),
        )),
        Err(_) => Err(ctx.err(
            ConfigErrorKind::BadNumber,
            format!("{field} must be a number, found '{tok}'"),
        )),
    }
}

/// A rate or period that must be greater than zero.
fn positive(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    let v = f32_field(ctx, field, tok)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be greater than 0, found {tok}"),
        ))
    }
}

/// A rate that may be zero (the fly trackers then use a 1-second interval).
fn non_negative(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    let v = f32_field(ctx, field, tok)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be 0 or more, found {tok}"),
        ))
    }
}

/// A baud rate from [`BAUD_RATES`].
fn baud(ctx: &Ctx<'_>, tok: &str) -> Result<u32, ConfigError> {
    let v = int_in(ctx, "baud", tok, i64::from(i32::MIN), i64::from(i32::MAX))?;
    match BAUD_RATES.iter().find(|&&b| i64::from(b) == v) {
        Some(&b) => Ok(b),
        None => Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!(
                "baud must be one of 300, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, \
                 found {tok}"
            ),
        )),
    }
}

/// A device name this server will publish under.
fn device_name(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<String, ConfigError> {
    if tok.contains('@') {
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!(
                "{field} '{tok}' must not contain '@' (clients connect to NAME@host, so the \
                 name itself cannot have one)"
            ),
        ));
    }
    if tok.len() > MAX_NAME_LEN {
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!(
                "{field} '{tok}' is {} characters long; VRPN names are at most {MAX_NAME_LEN}",
                tok.len()
            ),
        ));
    }
    Ok(tok.to_owned())
}

/// A reference to another device; `NULL` gives `None` when `allow_null`.
fn device_ref(
    ctx: &Ctx<'_>,
    field: &str,
    tok: &str,
    allow_null: bool,
) -> Result<Option<DeviceRef>, ConfigError> {
    if tok == "NULL" {
        if allow_null {
            return Ok(None);
        }
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!("{field} cannot be NULL here; name a device as *NAME or NAME@host"),
        ));
    }
    DeviceRef::parse(tok)
        .map(Some)
        .map_err(|why| ctx.err(ConfigErrorKind::BadName, format!("{field} '{tok}' {why}")))
}

// ---------------------------------------------------------------------------------------------
// Typed device configurations
// ---------------------------------------------------------------------------------------------

/// A reference from a layered device to the device it reads.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum DeviceRef {
    /// `*NAME`: a device served by this same server (the `*` is not stored).
    Local(String),
    /// `NAME@host[:port]`: a device on another server, stored whole.
    Remote(String),
}

impl DeviceRef {
    /// Parses `*NAME` or `NAME@host`; the error explains what is wrong (without the token).
    pub fn parse(tok: &str) -> Result<DeviceRef, String> {
        if let Some(name) = tok.strip_prefix('*') {
            if name.is_empty() {
                return Err("has nothing after the '*'; write *NAME".to_owned());
            }
            if name.contains('@') {
                return Err("mixes '*' (this server) with '@' (another server)".to_owned());
            }
            return Ok(DeviceRef::Local(name.to_owned()));
        }
        match tok.split_once('@') {
            Some((dev, host)) if !dev.is_empty() && !host.is_empty() => {
                Ok(DeviceRef::Remote(tok.to_owned()))
            }
            Some(_) => Err("must have a device name before and a host after the '@'".to_owned()),
            None => Err(format!(
                "must be *{tok} (a device of this server) or {tok}@host (a device on another \
                 server)"
            )),
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

/// A button of another device.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ButtonRef {
    /// The button device.
    pub device: DeviceRef,
    /// The button index on that device (0-based).
    pub button: u32,
}

/// `vrpn_Tracker_NULL NAME SENSORS RATE`: identity poses at a fixed rate.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerNull {
    /// Device name.
    pub name: String,
    /// Number of sensors, 1..=[`MAX_TRACKER_SENSORS`].
    pub sensors: u32,
    /// Reports per second, > 0.
    pub rate: f32,
}

/// `vrpn_Tracker_Spin NAME SENSORS RATE AXIS_X AXIS_Y AXIS_Z SPIN_HZ`: a tracker spinning
/// about an axis.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerSpin {
    /// Device name.
    pub name: String,
    /// Number of sensors, 1..=[`MAX_TRACKER_SENSORS`].
    pub sensors: u32,
    /// Reports per second, > 0.
    pub rate: f32,
    /// Rotation axis (need not be normalised; all zero gives the identity).
    pub axis: [f32; 3],
    /// Revolutions per second (negative spins the other way).
    pub spin_hz: f32,
}

/// `vrpn_Button_Example NAME BUTTONS RATE`: buttons that all flip together.
#[derive(Clone, Debug, PartialEq)]
pub struct ButtonExample {
    /// Device name.
    pub name: String,
    /// Number of buttons, 1..=[`MAX_BUTTONS`] (C++ clamps larger values; we reject them).
    pub buttons: u32,
    /// Transitions per second, > 0.
    pub rate: f32,
}

/// `vrpn_Dial_Example NAME DIALS SPIN_RATE UPDATE_RATE`: dials turning at a constant rate.
#[derive(Clone, Debug, PartialEq)]
pub struct DialExample {
    /// Device name.
    pub name: String,
    /// Number of dials, 1..=[`MAX_DIALS`].
    pub dials: u32,
    /// Revolutions per second of every dial (any sign).
    pub spin_rate: f32,
    /// Reports per second, > 0.
    pub update_rate: f32,
}

/// **Our extension** (not in C++ VRPN): `vrpn_Analog_Example NAME CHANNELS RATE`, an analog
/// server whose channels change over time, reporting `RATE` times per second.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalogExample {
    /// Device name.
    pub name: String,
    /// Number of channels, 1..=[`MAX_CHANNELS`].
    pub channels: u32,
    /// Reports per second, > 0.
    pub rate: f32,
}

/// **Our extension** (not in C++ VRPN): `vrpn_Text_Example NAME PERIOD_SECONDS MESSAGE...`,
/// a text sender that sends `MESSAGE` every `PERIOD_SECONDS`.
#[derive(Clone, Debug, PartialEq)]
pub struct TextExample {
    /// Device name.
    pub name: String,
    /// Seconds between messages, > 0.
    pub period: f32,
    /// The text: everything after the period, with surrounding blanks removed and inner
    /// spacing kept.
    pub message: String,
}

/// Whether a fly tracker's inputs are poses or rates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FlyMode {
    /// Inputs are positions / orientations.
    Absolute,
    /// Inputs are velocities / angular rates, integrated over time.
    Differential,
}

impl FlyMode {
    /// Parses `absolute` or `differential` (exact, lower case).
    pub fn parse(tok: &str) -> Option<FlyMode> {
        match tok {
            "absolute" => Some(FlyMode::Absolute),
            "differential" => Some(FlyMode::Differential),
            _ => None,
        }
    }
}

/// One of the six AnalogFly axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// Translation along x.
    X,
    /// Translation along y.
    Y,
    /// Translation along z.
    Z,
    /// Rotation about x.
    RX,
    /// Rotation about y.
    RY,
    /// Rotation about z.
    RZ,
}

impl Axis {
    /// All axes in the order C++ services them.
    pub const ALL: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::RX, Axis::RY, Axis::RZ];

    /// The axis keyword in an AnalogFly block (`X` .. `RZ`).
    pub fn keyword(self) -> &'static str {
        match self {
            Axis::X => "X",
            Axis::Y => "Y",
            Axis::Z => "Z",
            Axis::RX => "RX",
            Axis::RY => "RY",
            Axis::RZ => "RZ",
        }
    }

    /// Parses an axis keyword (case-sensitive, as in C++).
    pub fn from_keyword(tok: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|a| a.keyword() == tok)
    }

    /// Position in [`Axis::ALL`] and in [`AnalogFly::axes`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// One AnalogFly axis: which analog channel drives it and how its value is shaped.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalogFlyAxis {
    /// The analog device, or `None` (`NULL` or not configured): the axis stays 0.
    pub source: Option<DeviceRef>,
    /// Channel index on that device, 0..[`MAX_CHANNELS`].
    pub channel: u32,
    /// Subtracted from the channel value first.
    pub offset: f32,
    /// Values within ±threshold of the offset count as 0.
    pub threshold: f32,
    /// Multiplier, applied inside the power.
    pub scale: f32,
    /// Exponent.
    pub power: f32,
}

impl Default for AnalogFlyAxis {
    /// A disabled axis: no device, channel 0, offset 0, threshold 0, scale 1, power 1.
    fn default() -> Self {
        AnalogFlyAxis {
            source: None,
            channel: 0,
            offset: 0.0,
            threshold: 0.0,
            scale: 1.0,
            power: 1.0,
        }
    }
}

/// `vrpn_Tracker_AnalogFly NAME RATE absolute|differential` followed by axis, `RESET`,
/// `CLUTCH` and `WORLDFRAME` lines, ended by an empty line (LAYERED.md §2).
#[derive(Clone, Debug, PartialEq)]
pub struct AnalogFly {
    /// Device name of the produced tracker.
    pub name: String,
    /// Reports per second, >= 0 (0 means one report per second, as in C++).
    pub update_rate: f32,
    /// Absolute or differential.
    pub mode: FlyMode,
    /// Differential motion in the world frame (a `WORLDFRAME` line).
    pub world_frame: bool,
    /// The axes, indexed by [`Axis::index`]; unmentioned axes are disabled.
    pub axes: [AnalogFlyAxis; 6],
    /// Reset button (`RESET`), `None` when absent or `NULL`.
    pub reset: Option<ButtonRef>,
    /// Clutch button (`CLUTCH`), `None` when absent or `NULL` (always engaged).
    pub clutch: Option<ButtonRef>,
}

impl AnalogFly {
    /// The configuration of one axis.
    pub fn axis(&self, axis: Axis) -> &AnalogFlyAxis {
        &self.axes[axis.index()]
    }
}

/// One ButtonFly axis line (`absolute` or `differential`).
#[derive(Clone, Debug, PartialEq)]
pub struct ButtonFlyAxis {
    /// The button that drives it.
    pub button: ButtonRef,
    /// Absolute (jump to a pose) or differential (move while held).
    pub mode: FlyMode,
    /// Position in metres (absolute) or velocity in m/s (differential).
    pub vec: [f32; 3],
    /// Orientation in revolutions about x, y, z (absolute) or rev/s (differential).
    pub rot: [f32; 3],
}

/// A ButtonFly `vel_scale` / `rot_scale` analog.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleAnalog {
    /// The analog device.
    pub source: DeviceRef,
    /// Channel index, 0..[`MAX_CHANNELS`].
    pub channel: u32,
    /// Subtracted from the channel value first.
    pub offset: f32,
    /// Multiplier.
    pub scale: f32,
    /// Exponent.
    pub power: f32,
}

/// `vrpn_Tracker_ButtonFly NAME RATE` followed by `absolute`, `differential`, `vel_scale`,
/// `rot_scale` lines and a closing `end` line (LAYERED.md §3).
#[derive(Clone, Debug, PartialEq)]
pub struct ButtonFly {
    /// Device name of the produced tracker.
    pub name: String,
    /// Reports per second, >= 0 (0 means one report per second, as in C++).
    pub update_rate: f32,
    /// Axis lines in file order, at most [`MAX_BUTTONFLY_AXES`].
    pub axes: Vec<ButtonFlyAxis>,
    /// Analog scaling all translation rates (`vel_scale`), if any.
    pub vel_scale: Option<ScaleAnalog>,
    /// Analog scaling all rotation rates (`rot_scale`), if any.
    pub rot_scale: Option<ScaleAnalog>,
}

/// `vrpn_Joylin NAME DEVICE`: a Linux joystick (`/dev/input/jsN`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Joylin {
    /// Device name (Analog and Button under it).
    pub name: String,
    /// Joystick device path.
    pub device: String,
}

/// One step of the extra reset sequence of a Fastrak / InterSense entry (`\` lines).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ResetStep {
    /// `*N`: wait N seconds.
    Pause(u32),
    /// A command sent to the tracker, followed by a carriage return (not stored here).
    Command(String),
}

/// Clip values of one IS-900 wand joystick channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WandClip {
    /// Raw value mapped to -1.
    pub min: f64,
    /// Low end of the dead zone.
    pub low_zero: f64,
    /// High end of the dead zone.
    pub high_zero: f64,
    /// Raw value mapped to +1.
    pub max: f64,
}

/// A device attached to one station of a Fastrak / InterSense (`/` lines).
#[derive(Clone, Debug, PartialEq)]
pub enum StationDevice {
    /// `Wand NAME SENSOR C0MIN C0LO C0HI C0MAX C1MIN C1LO C1HI C1MAX`: IS-900 wand, an
    /// Analog (2 channels) and a Button (6) named `name`.
    Wand {
        /// Name of the wand's Analog and Button servers.
        name: String,
        /// Station (0-based).
        sensor: u32,
        /// Clip values of the joystick x and y channels.
        clip: [WandClip; 2],
    },
    /// `Stylus NAME SENSOR`: IS-900 stylus, a Button (2) named `name`.
    Stylus {
        /// Name of the stylus Button server.
        name: String,
        /// Station (0-based).
        sensor: u32,
    },
    /// `FTStylus NAME SENSOR`: genuine Fastrak stylus, a Button (1) named `name`; switches the
    /// driver into Fastrak button format.
    FtStylus {
        /// Name of the stylus Button server.
        name: String,
        /// Station (0-based).
        sensor: u32,
    },
}

impl StationDevice {
    /// The name of the servers this station device creates.
    pub fn name(&self) -> &str {
        match self {
            StationDevice::Wand { name, .. }
            | StationDevice::Stylus { name, .. }
            | StationDevice::FtStylus { name, .. } => name,
        }
    }

    /// The station it is attached to.
    pub fn sensor(&self) -> u32 {
        match self {
            StationDevice::Wand { sensor, .. }
            | StationDevice::Stylus { sensor, .. }
            | StationDevice::FtStylus { sensor, .. } => *sensor,
        }
    }
}

/// `vrpn_Tracker_Fastrak NAME PORT BAUD [IS900time|/|\]` plus optional `\` reset-command lines
/// and `/` station-device lines (CONFIG.md §5.2). Polhemus Fastrak, or an InterSense IS-600 /
/// IS-900 in Fastrak-compatible mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Fastrak {
    /// Device name.
    pub name: String,
    /// Serial port, passed to the OS unchanged.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`].
    pub baud: u32,
    /// IS-900 hardware timestamps (an option token starting with `IS900time`).
    pub is900_timestamps: bool,
    /// Extra reset commands, in order.
    pub reset_commands: Vec<ResetStep>,
    /// Station devices (wands, styluses), in order.
    pub stations: Vec<StationDevice>,
}

impl Fastrak {
    /// Stations vrpn_server configures (hard-wired in C++); station indexes are below this.
    pub const STATIONS: u32 = 4;

    /// Whether an `FTStylus` line switched the driver into genuine-Fastrak button format.
    pub fn really_fastrak(&self) -> bool {
        self.stations
            .iter()
            .any(|s| matches!(s, StationDevice::FtStylus { .. }))
    }
}

/// Port of a [`InterSense`] tracker.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum InterSensePort {
    /// `COM1` .. `COM4`.
    Com(u8),
    /// `AUTO`: let the SDK search.
    Auto,
}

/// `vrpn_Tracker_InterSense NAME COM1..COM4|AUTO [IS900time] [ResetAtStartup] [/|\]` plus the
/// same continuation lines as [`Fastrak`] (CONFIG.md §5.3; needs InterSense's SDK). This is the
/// only IS-900-specific keyword: there is no `vrpn_Tracker_IS900` in VRPN 07.35.
#[derive(Clone, Debug, PartialEq)]
pub struct InterSense {
    /// Device name.
    pub name: String,
    /// Port.
    pub port: InterSensePort,
    /// IS-900 hardware timestamps (`IS900time`).
    pub is900_timestamps: bool,
    /// Reset the tracker when the server starts (`ResetAtStartup`).
    pub reset_at_startup: bool,
    /// Extra reset commands, in order.
    pub reset_commands: Vec<ResetStep>,
    /// Station devices (wands, styluses), in order.
    pub stations: Vec<StationDevice>,
}

impl InterSense {
    /// Stations we accept (the SDK's `ISD_MAX_STATIONS`); station indexes are below this.
    pub const STATIONS: u32 = 8;
}

/// Hemisphere a Flock of Birds works in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hemisphere {
    /// `+x`.
    PosX,
    /// `-x`.
    NegX,
    /// `+y`.
    PosY,
    /// `-y`.
    NegY,
    /// `+z` (the default).
    PosZ,
    /// `-z`.
    NegZ,
}

impl Hemisphere {
    /// Parses `+x -x +y -y +z -z` (axis letter in either case).
    pub fn parse(tok: &str) -> Option<Hemisphere> {
        match tok.to_ascii_lowercase().as_str() {
            "+x" => Some(Hemisphere::PosX),
            "-x" => Some(Hemisphere::NegX),
            "+y" => Some(Hemisphere::PosY),
            "-y" => Some(Hemisphere::NegY),
            "+z" => Some(Hemisphere::PosZ),
            "-z" => Some(Hemisphere::NegZ),
            _ => None,
        }
    }
}

/// `vrpn_Tracker_Flock NAME SENSORS PORT BAUD INVERT [USE_ERT] [HEMISPHERE]`: Ascension Flock
/// of Birds on one serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Flock {
    /// Device name.
    pub name: String,
    /// Number of receivers, 1..=[`MAX_FLOCK_SENSORS`].
    pub sensors: u32,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`].
    pub baud: u32,
    /// Report the inverse quaternion (non-zero INVERT).
    pub invert_quaternion: bool,
    /// Extended-range transmitter present (default yes; a token starting with `n`/`N` = no).
    pub use_ert: bool,
    /// Hemisphere (default `+z`).
    pub hemisphere: Hemisphere,
}

/// `vrpn_Tracker_Flock_Parallel NAME SENSORS MASTER_PORT BAUD INVERT PORT_1 .. PORT_N`: one
/// serial line per receiver.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FlockParallel {
    /// Device name.
    pub name: String,
    /// Number of receivers N, 1..=[`MAX_FLOCK_SENSORS`] (C++ 07.35 does not check; later
    /// versions reject more than 13, as we do).
    pub sensors: u32,
    /// Master's serial port.
    pub master_port: String,
    /// Baud rate of all ports, one of [`BAUD_RATES`].
    pub baud: u32,
    /// The INVERT flag; C++ applies it only to the master, so it changes nothing reported.
    pub invert_quaternion: bool,
    /// One serial port per receiver (N of them).
    pub slave_ports: Vec<String>,
}

/// `vrpn_Magellan NAME PORT BAUD [altreset]`: Magellan / SpaceMouse on a serial port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Magellan {
    /// Device name (Analog with 6 channels, Button with 9).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`] (the device documents 9600).
    pub baud: u32,
    /// Use the alternate reset string of older units (`altreset`).
    pub alt_reset: bool,
}

/// `vrpn_CerealBox NAME PORT BAUD BUTTONS ANALOGS ENCODERS`: BG Systems CerealBox.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CerealBox {
    /// Device name (Button, Analog and Dial under it).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`] (the device documents 19200).
    pub baud: u32,
    /// Buttons, 0..=24 (C++ clamps larger values; we reject them).
    pub buttons: u32,
    /// Analog channels, 0..=8.
    pub analogs: u32,
    /// Encoders (dials), 0..=8.
    pub encoders: u32,
}

impl CerealBox {
    /// Most buttons.
    pub const MAX_BUTTONS: u32 = 24;
    /// Most analogs.
    pub const MAX_ANALOGS: u32 = 8;
    /// Most encoders.
    pub const MAX_ENCODERS: u32 = 8;
}

/// `vrpn_Tracker_Dyna NAME SENSORS PORT BAUD`: Origin Instruments DynaSight (note: sensor
/// count before the port).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Dyna {
    /// Device name.
    pub name: String,
    /// Sensor count, 1..=[`MAX_FLOCK_SENSORS`] (only sensor 0 is ever reported).
    pub sensors: u32,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`].
    pub baud: u32,
}

/// One configured device, by type.
#[derive(Clone, Debug, PartialEq)]
pub enum DeviceConfig {
    /// `vrpn_Tracker_NULL`.
    TrackerNull(TrackerNull),
    /// `vrpn_Tracker_Spin`.
    TrackerSpin(TrackerSpin),
    /// `vrpn_Button_Example`.
    ButtonExample(ButtonExample),
    /// `vrpn_Dial_Example`.
    DialExample(DialExample),
    /// `vrpn_Analog_Example` (our extension).
    AnalogExample(AnalogExample),
    /// `vrpn_Text_Example` (our extension).
    TextExample(TextExample),
    /// `vrpn_Tracker_AnalogFly` (boxed: it is much larger than the others).
    AnalogFly(Box<AnalogFly>),
    /// `vrpn_Tracker_ButtonFly`.
    ButtonFly(ButtonFly),
    /// `vrpn_Joylin`.
    Joylin(Joylin),
    /// `vrpn_Tracker_Fastrak`.
    Fastrak(Fastrak),
    /// `vrpn_Tracker_InterSense`.
    InterSense(InterSense),
    /// `vrpn_Tracker_Flock`.
    Flock(Flock),
    /// `vrpn_Tracker_Flock_Parallel`.
    FlockParallel(FlockParallel),
    /// `vrpn_Magellan`.
    Magellan(Magellan),
    /// `vrpn_CerealBox`.
    CerealBox(CerealBox),
    /// `vrpn_Tracker_Dyna`.
    Dyna(Dyna),
    /// A keyword we do not know. C++ `vrpn_server` stops on it by default and skips it with
    /// `-warn`; see [`DeviceEntry::unknown_error`].
    Unknown {
        /// The first token of the line (empty for a line of only blanks).
        keyword: String,
        /// The remaining tokens.
        args: Vec<String>,
    },
}

impl DeviceConfig {
    /// The `vrpn.cfg` keyword of this entry.
    pub fn keyword(&self) -> &str {
        match self {
            DeviceConfig::TrackerNull(_) => kw::TRACKER_NULL,
            DeviceConfig::TrackerSpin(_) => kw::TRACKER_SPIN,
            DeviceConfig::ButtonExample(_) => kw::BUTTON_EXAMPLE,
            DeviceConfig::DialExample(_) => kw::DIAL_EXAMPLE,
            DeviceConfig::AnalogExample(_) => kw::ANALOG_EXAMPLE,
            DeviceConfig::TextExample(_) => kw::TEXT_EXAMPLE,
            DeviceConfig::AnalogFly(_) => kw::ANALOG_FLY,
            DeviceConfig::ButtonFly(_) => kw::BUTTON_FLY,
            DeviceConfig::Joylin(_) => kw::JOYLIN,
            DeviceConfig::Fastrak(_) => kw::FASTRAK,
            DeviceConfig::InterSense(_) => kw::INTERSENSE,
            DeviceConfig::Flock(_) => kw::FLOCK,
            DeviceConfig::FlockParallel(_) => kw::FLOCK_PARALLEL,
            DeviceConfig::Magellan(_) => kw::MAGELLAN,
            DeviceConfig::CerealBox(_) => kw::CEREALBOX,
            DeviceConfig::Dyna(_) => kw::DYNA,
            DeviceConfig::Unknown { keyword, .. } => keyword,
        }
    }

    /// The device's name (`None` for [`DeviceConfig::Unknown`]).
    pub fn name(&self) -> Option<&str> {
        Some(match self {
            DeviceConfig::TrackerNull(d) => &d.name,
            DeviceConfig::TrackerSpin(d) => &d.name,
            DeviceConfig::ButtonExample(d) => &d.name,
            DeviceConfig::DialExample(d) => &d.name,
            DeviceConfig::AnalogExample(d) => &d.name,
            DeviceConfig::TextExample(d) => &d.name,
            DeviceConfig::AnalogFly(d) => &d.name,
            DeviceConfig::ButtonFly(d) => &d.name,
            DeviceConfig::Joylin(d) => &d.name,
            DeviceConfig::Fastrak(d) => &d.name,
            DeviceConfig::InterSense(d) => &d.name,
            DeviceConfig::Flock(d) => &d.name,
            DeviceConfig::FlockParallel(d) => &d.name,
            DeviceConfig::Magellan(d) => &d.name,
            DeviceConfig::CerealBox(d) => &d.name,
            DeviceConfig::Dyna(d) => &d.name,
            DeviceConfig::Unknown { .. } => return None,
        })
    }

    /// Every name this entry publishes under: its own and those of its station devices.
    pub fn device_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.name().into_iter().collect();
        let stations = match self {
            DeviceConfig::Fastrak(d) => &d.stations[..],
            DeviceConfig::InterSense(d) => &d.stations[..],
            _ => &[],
        };
        names.extend(stations.iter().map(StationDevice::name));
        names
    }
}

/// One entry of `vrpn.cfg`.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceEntry {
    /// Where the entry starts.
    pub location: SourceLocation,
    /// Last line the entry used (differs from `location.line` for multi-line entries).
    pub last_line: usize,
    /// The keyword as written (for [`DeviceConfig::Unknown`], the unrecognised one).
    pub keyword: String,
    /// The tokens after the keyword on the first line.
    pub args: Vec<String>,
    /// The parsed configuration.
    pub config: DeviceConfig,
}

impl DeviceEntry {
    /// For an [`DeviceConfig::Unknown`] entry, the error to report: C++ `vrpn_server` stops
    /// with "Unknown Device" by default, and with `-warn` prints it and skips the line (print
    /// this error followed by `, skipped`). `None` for known entries.
    pub fn unknown_error(&self) -> Option<ConfigError> {
        let DeviceConfig::Unknown { keyword, .. } = &self.config else {
            return None;
        };
        let message = unknown_message(keyword);
        Some(ConfigError::at_line(
            ConfigErrorKind::UnknownDevice,
            &self.location.file,
            self.location.line,
            message,
        ))
    }
}

/// The explanation for an unknown keyword, with a hint where we can guess the intent.
fn unknown_message(keyword: &str) -> String {
    if keyword.is_empty() {
        return "line contains only blanks; C++ vrpn_server treats it as an unknown device, so \
                make it truly empty"
            .to_owned();
    }
    let base = format!("unknown device type {keyword}");
    if let Some(stripped) = keyword.strip_prefix('\u{feff}') {
        return format!(
            "{base}: the file starts with a byte-order mark before '{stripped}'; save it \
             without BOM"
        );
    }
    if KNOWN_KEYWORDS.contains(&keyword) {
        return format!(
            "{base}: a character other than a space or tab (such as a carriage return) follows \
             the keyword; separate it from its arguments with spaces or tabs"
        );
    }
    if keyword == "vrpn_Tracker_IS900" {
        return format!(
            "{base}: VRPN has no such keyword; run an IS-900 with vrpn_Tracker_Fastrak NAME \
             PORT BAUD IS900time (or vrpn_Tracker_InterSense)"
        );
    }
    if let Some(known) = KNOWN_KEYWORDS
        .iter()
        .find(|k| k.eq_ignore_ascii_case(keyword))
    {
        return format!("{base}: keywords are case-sensitive, did you mean {known}?");
    }
    base
}

/// Result of [`parse_str_lenient`]: the entries that parsed and the problems with the rest.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParseReport {
    /// Entries that parsed, in file order (unknown ones included).
    pub entries: Vec<DeviceEntry>,
    /// One error per skipped entry or line, in file order.
    pub errors: Vec<ConfigError>,
}

// ---------------------------------------------------------------------------------------------
// Entry parsers
// ---------------------------------------------------------------------------------------------

fn parse_tracker_null(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, sensors, rate")?;
    Ok(DeviceConfig::TrackerNull(TrackerNull {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_TRACKER_SENSORS)?,
        rate: positive(ctx, "rate", a[2])?,
    }))
}

fn parse_tracker_spin(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(
        ctx,
        a,
        7,
        "name, sensors, rate, axis_x, axis_y, axis_z, spin_hz",
    )?;
    Ok(DeviceConfig::TrackerSpin(TrackerSpin {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_TRACKER_SENSORS)?,
        rate: positive(ctx, "rate", a[2])?,
        axis: [
            f32_field(ctx, "axis_x", a[3])?,
            f32_field(ctx, "axis_y", a[4])?,
            f32_field(ctx, "axis_z", a[5])?,
        ],
        spin_hz: f32_field(ctx, "spin_hz", a[6])?,
    }))
}

fn parse_button_example(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, buttons, rate")?;
    Ok(DeviceConfig::ButtonExample(ButtonExample {
        name: device_name(ctx, "name", a[0])?,
        buttons: uint_in(ctx, "buttons", a[1], 1, MAX_BUTTONS)?,
        rate: positive(ctx, "rate", a[2])?,
    }))
}

fn parse_dial_example(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 4, "name, dials, spin_rate, update_rate")?;
    Ok(DeviceConfig::DialExample(DialExample {
        name: device_name(ctx, "name", a[0])?,
        dials: uint_in(ctx, "dials", a[1], 1, MAX_DIALS)?,
        spin_rate: f32_field(ctx, "spin_rate", a[2])?,
        update_rate: positive(ctx, "update_rate", a[3])?,
    }))
}

fn parse_analog_example(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, channels, rate")?;
    Ok(DeviceConfig::AnalogExample(AnalogExample {
        name: device_name(ctx, "name", a[0])?,
        channels: uint_in(ctx, "channels", a[1], 1, MAX_CHANNELS)?,
        rate: positive(ctx, "rate", a[2])?,
    }))
}

/// The text of `rest` from its `n`th token (0-based) on, blanks around it removed.
fn from_token(rest: &str, n: usize) -> &str {
    let mut s = rest.trim_start_matches(is_c_space);
    for _ in 0..n {
        let end = s.find(is_c_space).unwrap_or(s.len());
        s = s[end..].trim_start_matches(is_c_space);
    }
    s.trim_end_matches(is_c_space)
}

fn parse_text_example(ctx: &Ctx<'_>, a: &[&str], rest: &str) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, period_seconds, message")?;
    Ok(DeviceConfig::TextExample(TextExample {
        name: device_name(ctx, "name", a[0])?,
        period: positive(ctx, "period_seconds", a[1])?,
        message: from_token(rest, 2).to_owned(),
    }))
}

fn parse_joylin(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 2, "name, device")?;
    Ok(DeviceConfig::Joylin(Joylin {
        name: device_name(ctx, "name", a[0])?,
        device: a[1].to_owned(),
    }))
}

fn parse_flock(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(
        ctx,
        a,
        5,
        "name, sensors, port, baud, invert_quaternion, [useERT], [hemisphere]",
    )?;
    let use_ert = a.get(5).map_or(true, |t| !t.starts_with(['n', 'N']));
    let hemisphere = match a.get(6) {
        None => Hemisphere::PosZ,
        Some(t) => Hemisphere::parse(t).ok_or_else(|| {
            ctx.err(
                ConfigErrorKind::BadValue,
                format!("hemisphere must be one of +x -x +y -y +z -z, found '{t}'"),
            )
        })?,
    };
    Ok(DeviceConfig::Flock(Flock {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_FLOCK_SENSORS)?,
        port: a[2].to_owned(),
        baud: baud(ctx, a[3])?,
        invert_quaternion: any_int(ctx, "invert_quaternion", a[4])? != 0,
        use_ert,
        hemisphere,
    }))
}

fn parse_flock_parallel(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    const USAGE: &str = "name, sensors, master_port, baud, invert_quaternion, then one port \
                         per sensor";
    need(ctx, a, 5, USAGE)?;
    let sensors = uint_in(ctx, "sensors", a[1], 1, MAX_FLOCK_SENSORS)?;
    let ports = &a[5..];
    let wanted = sensors as usize;
    if ports.len() < wanted {
        return Err(ctx.err(
            ConfigErrorKind::MissingArguments,
            format!(
                "expected {wanted} slave port name(s) after invert_quaternion (one per \
                 sensor), found {}",
                ports.len()
            ),
        ));
    }
    Ok(DeviceConfig::FlockParallel(FlockParallel {
        name: device_name(ctx, "name", a[0])?,
        sensors,
        master_port: a[2].to_owned(),
        baud: baud(ctx, a[3])?,
        invert_quaternion: any_int(ctx, "invert_quaternion", a[4])? != 0,
        slave_ports: ports[..wanted].iter().map(|p| (*p).to_owned()).collect(),
    }))
}

fn parse_magellan(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, port, baud, [altreset]")?;
    let alt_reset = match a.get(3) {
        None => false,
        Some(&"altreset") => true,
        Some(t) => {
            return Err(ctx.err(
                ConfigErrorKind::BadValue,
                format!("the optional 4th argument must be 'altreset', found '{t}'"),
            ))
        }
    };
    Ok(DeviceConfig::Magellan(Magellan {
        name: device_name(ctx, "name", a[0])?,
        port: a[1].to_owned(),
        baud: baud(ctx, a[2])?,
        alt_reset,
    }))
}

fn parse_cerealbox(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 6, "name, port, baud, buttons, analogs, encoders")?;
    Ok(DeviceConfig::CerealBox(CerealBox {
        name: device_name(ctx, "name", a[0])?,
        port: a[1].to_owned(),
        baud: baud(ctx, a[2])?,
        buttons: uint_in(ctx, "buttons", a[3], 0, CerealBox::MAX_BUTTONS)?,
        analogs: uint_in(ctx, "analogs", a[4], 0, CerealBox::MAX_ANALOGS)?,
        encoders: uint_in(ctx, "encoders", a[5], 0, CerealBox::MAX_ENCODERS)?,
    }))
}

fn parse_dyna(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 4, "name, sensors, port, baud")?;
    Ok(DeviceConfig::Dyna(Dyna {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_FLOCK_SENSORS)?,
        port: a[2].to_owned(),
        baud: baud(ctx, a[3])?,
    }))
}

// --- AnalogFly --------------------------------------------------------------------------------

fn parse_analog_fly(
    ctx: &Ctx<'_>,
    a: &[&str],
    reader: &mut Reader<'_>,
) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, update_rate, absolute|differential")?;
    let name = device_name(ctx, "name", a[0])?;
    let update_rate = non_negative(ctx, "update_rate", a[1])?;
    let mode = FlyMode::parse(a[2]).ok_or_else(|| {
        ctx.err(
            ConfigErrorKind::BadValue,
            format!(
                "the third argument must be 'absolute' or 'differential', found '{}'",
                a[2]
            ),
        )
    })?;
    let mut fly = AnalogFly {
        name,
        update_rate,
        mode,
        world_frame: false,
        axes: Default::default(),
        reset: None,
        clutch: None,
    };
    let block = Ctx::new(
        ctx.file,
        ctx.line,
        format!("{} {}", kw::ANALOG_FLY, fly.name),
    );
    loop {
        let line = reader.block_line(
            &block,
            "the empty line that must end the block (add an empty line after its last line)",
        )?;
        // Only a truly empty line ends the block (not blanks, not "\r\n").
        if line.text.starts_with('\n') {
            return Ok(DeviceConfig::AnalogFly(Box::new(fly)));
        }
        analog_fly_line(&block.at(line.number), &c_tokens(line.text), &mut fly)?;
    }
}

/// Applies one line of an AnalogFly block; unknown first tokens are ignored, as in C++.
fn analog_fly_line(ctx: &Ctx<'_>, t: &[&str], fly: &mut AnalogFly) -> Result<(), ConfigError> {
    let Some(&first) = t.first() else {
        return Ok(());
    };
    if let Some(axis) = Axis::from_keyword(first) {
        fly.axes[axis.index()] = analog_fly_axis(ctx, first, &t[1..])?;
    } else if first == "RESET" || first == "CLUTCH" {
        let button = button_line(ctx, first, &t[1..])?;
        if first == "RESET" {
            fly.reset = button;
        } else {
            fly.clutch = button;
        }
    } else if first == "WORLDFRAME" {
        fly.world_frame = true;
    }
    Ok(())
}

fn block_need(
    ctx: &Ctx<'_>,
    line_kw: &str,
    t: &[&str],
    n: usize,
    usage: &str,
) -> Result<(), ConfigError> {
    if t.len() >= n {
        return Ok(());
    }
    Err(ctx.err(
        ConfigErrorKind::BadBlockLine,
        format!(
            "{line_kw} line needs {n} values after '{line_kw}' ({usage}), found {}",
            t.len()
        ),
    ))
}

fn analog_fly_axis(ctx: &Ctx<'_>, axis: &str, t: &[&str]) -> Result<AnalogFlyAxis, ConfigError> {
    block_need(
        ctx,
        axis,
        t,
        6,
        "device or NULL, channel, offset, threshold, scale, power",
    )?;
    let field = |f: &str| format!("axis {axis} {f}");
    Ok(AnalogFlyAxis {
        source: device_ref(ctx, &field("device"), t[0], true)?,
        channel: uint_in(ctx, &field("channel"), t[1], 0, MAX_CHANNELS - 1)?,
        offset: f32_field(ctx, &field("offset"), t[2])?,
        threshold: f32_field(ctx, &field("threshold"), t[3])?,
        scale: f32_field(ctx, &field("scale"), t[4])?,
        power: f32_field(ctx, &field("power"), t[5])?,
    })
}

/// A `RESET` / `CLUTCH` line: `NULL` gives `None`.
fn button_line(ctx: &Ctx<'_>, what: &str, t: &[&str]) -> Result<Option<ButtonRef>, ConfigError> {
    block_need(ctx, what, t, 2, "button device or NULL, button index")?;
    let device = device_ref(ctx, &format!("{what} device"), t[0], true)?;
    let button = uint_in(
        ctx,
        &format!("{what} button index"),
        t[1],
        0,
        MAX_BUTTONS - 1,
    )?;
    Ok(device.map(|device| ButtonRef { device, button }))
}

// --- ButtonFly --------------------------------------------------------------------------------

fn parse_button_fly(
    ctx: &Ctx<'_>,
    a: &[&str],
    reader: &mut Reader<'_>,
) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 2, "name, update_rate")?;
    let mut fly = ButtonFly {
        name: device_name(ctx, "name", a[0])?,
        update_rate: non_negative(ctx, "update_rate", a[1])?,
        axes: Vec::new(),
        vel_scale: None,
        rot_scale: None,
    };
    let block = Ctx::new(
        ctx.file,
        ctx.line,
        format!("{} {}", kw::BUTTON_FLY, fly.name),
    );
    loop {
        let line = reader.block_line(&block, "the 'end' line that must close the block")?;
        let here = block.at(line.number);
        let t = c_tokens(line.text);
        match t.first().copied() {
            None => {
                return Err(here.err(
                    ConfigErrorKind::BadBlockLine,
                    "empty line inside the block; remove it (the block ends at a line 'end')",
                ))
            }
            Some("end") => return Ok(DeviceConfig::ButtonFly(fly)),
            Some(m @ ("absolute" | "differential")) => {
                if fly.axes.len() >= MAX_BUTTONFLY_AXES {
                    return Err(here.err(
                        ConfigErrorKind::BadBlockLine,
                        format!("too many axis lines; at most {MAX_BUTTONFLY_AXES} are allowed"),
                    ));
                }
                fly.axes.push(button_fly_axis(&here, m, &t[1..])?);
            }
            Some(s @ ("vel_scale" | "rot_scale")) => {
                let scale = scale_analog(&here, s, &t[1..])?;
                if s == "vel_scale" {
                    fly.vel_scale = scale;
                } else {
                    fly.rot_scale = scale;
                }
            }
            Some(_) => {}
        }
    }
}

fn button_fly_axis(ctx: &Ctx<'_>, mode: &str, t: &[&str]) -> Result<ButtonFlyAxis, ConfigError> {
    block_need(
        ctx,
        mode,
        t,
        8,
        "button device, button index, x, y, z, rx, ry, rz",
    )?;
    if t[0].len() > MAX_BUTTONFLY_NAME {
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!(
                "button device name is {} characters long; at most {MAX_BUTTONFLY_NAME} allowed",
                t[0].len()
            ),
        ));
    }
    let device = device_ref(ctx, "button device", t[0], false)?
        .ok_or_else(|| ctx.err(ConfigErrorKind::BadName, "button device cannot be NULL"))?;
    let f = |i: usize, name: &str| f32_field(ctx, name, t[i]);
    Ok(ButtonFlyAxis {
        button: ButtonRef {
            device,
            button: uint_in(ctx, "button index", t[1], 0, MAX_BUTTONS - 1)?,
        },
        mode: FlyMode::parse(mode).unwrap_or(FlyMode::Differential),
        vec: [f(2, "x")?, f(3, "y")?, f(4, "z")?],
        rot: [f(5, "rx")?, f(6, "ry")?, f(7, "rz")?],
    })
}

fn scale_analog(ctx: &Ctx<'_>, what: &str, t: &[&str]) -> Result<Option<ScaleAnalog>, ConfigError> {
    block_need(
        ctx,
        what,
        t,
        5,
        "analog device or NULL, channel, offset, scale, power",
    )?;
    let Some(source) = device_ref(ctx, &format!("{what} device"), t[0], true)? else {
        return Ok(None);
    };
    Ok(Some(ScaleAnalog {
        source,
        channel: uint_in(ctx, &format!("{what} channel"), t[1], 0, MAX_CHANNELS - 1)?,
        offset: f32_field(ctx, &format!("{what} offset"), t[2])?,
        scale: f32_field(ctx, &format!("{what} scale"), t[3])?,
        power: f32_field(ctx, &format!("{what} power"), t[4])?,
    }))
}

// --- Fastrak / InterSense ---------------------------------------------------------------------

/// Splits a trailing continuation character (`\` or `/`, the very last character before the
/// newline) off a line's content.
fn split_continuation(content: &str) -> (&str, Option<char>) {
    match content.chars().last() {
        Some(c @ ('\\' | '/')) => (&content[..content.len() - 1], Some(c)),
        _ => (content, None),
    }
}

/// Continuation lines after a Fastrak / InterSense first line ending in `cont`.
struct Continuations {
    reset_commands: Vec<ResetStep>,
    stations: Vec<StationDevice>,
}

fn read_continuations(
    ctx: &Ctx<'_>,
    mut cont: Option<char>,
    stations_max: u32,
    reader: &mut Reader<'_>,
) -> Result<Continuations, ConfigError> {
    let mut out = Continuations {
        reset_commands: Vec::new(),
        stations: Vec::new(),
    };
    let mut reset_len = 0usize;
    while cont == Some('\\') {
        let line = reader.block_line(ctx, "the reset command promised by the trailing '\\'")?;
        let (body, next) = split_continuation(line.content());
        reset_len += body.len() + 1;
        if reset_len > MAX_RESET_COMMANDS {
            return Err(ctx.at(line.number).err(
                ConfigErrorKind::BadBlockLine,
                format!("reset commands exceed {MAX_RESET_COMMANDS} characters in total"),
            ));
        }
        out.reset_commands
            .push(reset_step(&ctx.at(line.number), body)?);
        cont = next;
    }
    while cont == Some('/') {
        let line =
            reader.block_line(ctx, "the station device line promised by the trailing '/'")?;
        let (body, next) = split_continuation(line.content());
        let here = ctx.at(line.number);
        let station = station_device(&here, &c_tokens(body), stations_max)?;
        if let Some(other) = out.stations.iter().find(|s| s.sensor() == station.sensor()) {
            return Err(here.err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "station {} already has device '{}'",
                    station.sensor(),
                    other.name()
                ),
            ));
        }
        out.stations.push(station);
        cont = next;
    }
    Ok(out)
}

fn reset_step(ctx: &Ctx<'_>, body: &str) -> Result<ResetStep, ConfigError> {
    let Some(secs) = body.strip_prefix('*') else {
        return Ok(ResetStep::Command(body.to_owned()));
    };
    let secs = secs.trim_matches(is_c_space);
    uint_in(ctx, "reset pause (*N, in seconds)", secs, 0, 3600).map(ResetStep::Pause)
}

fn station_device(ctx: &Ctx<'_>, t: &[&str], stations: u32) -> Result<StationDevice, ConfigError> {
    let Some(&first) = t.first() else {
        return Err(ctx.err(
            ConfigErrorKind::BadBlockLine,
            "empty station device line; expected Wand, Stylus or FTStylus",
        ));
    };
    let max = stations - 1;
    match first {
        "Wand" => {
            block_need(
                ctx,
                first,
                t,
                11,
                "name, sensor, c0min, c0lo, c0hi, c0max, c1min, c1lo, c1hi, c1max",
            )?;
            let name = device_name(ctx, "Wand name", t[1])?;
            let sensor = uint_in(ctx, "Wand sensor", t[2], 0, max)?;
            let clip0 = wand_clip(ctx, 0, &t[3..7])?;
            let clip1 = wand_clip(ctx, 1, &t[7..11])?;
            Ok(StationDevice::Wand {
                name,
                sensor,
                clip: [clip0, clip1],
            })
        }
        "Stylus" | "FTStylus" => {
            block_need(ctx, first, t, 3, "name, sensor")?;
            let name = device_name(ctx, &format!("{first} name"), t[1])?;
            let sensor = uint_in(ctx, &format!("{first} sensor"), t[2], 0, max)?;
            Ok(if first == "Stylus" {
                StationDevice::Stylus { name, sensor }
            } else {
                StationDevice::FtStylus { name, sensor }
            })
        }
        other => Err(ctx.err(
            ConfigErrorKind::BadBlockLine,
            format!("unknown station device '{other}'; expected Wand, Stylus or FTStylus"),
        )),
    }
}

fn wand_clip(ctx: &Ctx<'_>, channel: usize, t: &[&str]) -> Result<WandClip, ConfigError> {
    let f = |i: usize, what: &str| f64_field(ctx, &format!("Wand channel {channel} {what}"), t[i]);
    let clip = WandClip {
        min: f(0, "min")?,
        low_zero: f(1, "lowzero")?,
        high_zero: f(2, "highzero")?,
        max: f(3, "max")?,
    };
    if clip.min <= clip.low_zero && clip.low_zero <= clip.high_zero && clip.high_zero <= clip.max {
        Ok(clip)
    } else {
        Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!(
                "Wand channel {channel} clip values must satisfy min <= lowzero <= highzero <= \
                 max, found {} {} {} {}",
                t[0], t[1], t[2], t[3]
            ),
        ))
    }
}

fn parse_fastrak(
    ctx: &Ctx<'_>,
    rest: &str,
    reader: &mut Reader<'_>,
) -> Result<DeviceConfig, ConfigError> {
    let (head, cont) = split_continuation(rest.strip_suffix('\n').unwrap_or(rest));
    let a = c_tokens(head);
    need(ctx, &a, 3, "name, port, baud, [IS900time | / | \\]")?;
    let name = device_name(ctx, "name", a[0])?;
    let port = a[1].to_owned();
    let baud = baud(ctx, a[2])?;
    let is900_timestamps = match a.get(3) {
        None => false,
        Some(t) if t.starts_with("IS900time") => true,
        Some(&("/" | "\\")) => false,
        Some(t) => {
            return Err(ctx.err(
                ConfigErrorKind::BadValue,
                format!("the optional 4th argument must be IS900time, '/' or '\\', found '{t}'"),
            ))
        }
    };
    let more = read_continuations(ctx, cont, Fastrak::STATIONS, reader)?;
    Ok(DeviceConfig::Fastrak(Fastrak {
        name,
        port,
        baud,
        is900_timestamps,
        reset_commands: more.reset_commands,
        stations: more.stations,
    }))
}

fn parse_intersense(
    ctx: &Ctx<'_>,
    rest: &str,
    reader: &mut Reader<'_>,
) -> Result<DeviceConfig, ConfigError> {
    let (head, cont) = split_continuation(rest.strip_suffix('\n').unwrap_or(rest));
    let a = c_tokens(head);
    need(
        ctx,
        &a,
        2,
        "name, COM1..COM4 or AUTO, [IS900time] [ResetAtStartup]",
    )?;
    let name = device_name(ctx, "name", a[0])?;
    let port = match a[1] {
        "AUTO" => InterSensePort::Auto,
        "COM1" => InterSensePort::Com(1),
        "COM2" => InterSensePort::Com(2),
        "COM3" => InterSensePort::Com(3),
        "COM4" => InterSensePort::Com(4),
        other => {
            return Err(ctx.err(
                ConfigErrorKind::BadValue,
                format!("port must be COM1, COM2, COM3, COM4 or AUTO, found '{other}'"),
            ))
        }
    };
    let (mut is900_timestamps, mut reset_at_startup) = (false, false);
    for opt in a.iter().skip(2).take(3) {
        match *opt {
            "IS900time" => is900_timestamps = true,
            "ResetAtStartup" => reset_at_startup = true,
            "/" | "\\" => {}
            other => {
                return Err(ctx.err(
                    ConfigErrorKind::BadValue,
                    format!(
                        "options must be IS900time, ResetAtStartup, '/' or '\\', found '{other}'"
                    ),
                ))
            }
        }
    }
    let more = read_continuations(ctx, cont, InterSense::STATIONS, reader)?;
    Ok(DeviceConfig::InterSense(InterSense {
        name,
        port,
        is900_timestamps,
        reset_at_startup,
        reset_commands: more.reset_commands,
        stations: more.stations,
    }))
}

// ---------------------------------------------------------------------------------------------
// Top level
// ---------------------------------------------------------------------------------------------

/// Parses the entry whose first line is `line`, reading block lines from `reader`.
fn parse_entry(
    file: &str,
    line: RawLine<'_>,
    tokens: &EntryTokens<'_>,
    reader: &mut Reader<'_>,
) -> Result<DeviceEntry, ConfigError> {
    let ctx = Ctx::new(file, line.number, tokens.keyword);
    let a = &tokens.args[..];
    let known = KNOWN_KEYWORDS.contains(&tokens.keyword);
    let config = if !known || (!tokens.matchable && !a.is_empty()) {
        // C++ prints "Unknown Device" for it. A known keyword alone on its line is also
        // "unknown" to C++; it falls through to the argument-count error below instead.
        DeviceConfig::Unknown {
            keyword: tokens.keyword.to_owned(),
            args: a.iter().map(|s| (*s).to_owned()).collect(),
        }
    } else {
        match tokens.keyword {
            kw::TRACKER_NULL => parse_tracker_null(&ctx, a)?,
            kw::TRACKER_SPIN => parse_tracker_spin(&ctx, a)?,
            kw::BUTTON_EXAMPLE => parse_button_example(&ctx, a)?,
            kw::DIAL_EXAMPLE => parse_dial_example(&ctx, a)?,
            kw::ANALOG_EXAMPLE => parse_analog_example(&ctx, a)?,
            kw::TEXT_EXAMPLE => parse_text_example(&ctx, a, tokens.rest)?,
            kw::ANALOG_FLY => parse_analog_fly(&ctx, a, reader)?,
            kw::BUTTON_FLY => parse_button_fly(&ctx, a, reader)?,
            kw::JOYLIN => parse_joylin(&ctx, a)?,
            kw::FASTRAK => parse_fastrak(&ctx, tokens.rest, reader)?,
            kw::INTERSENSE => parse_intersense(&ctx, tokens.rest, reader)?,
            kw::FLOCK => parse_flock(&ctx, a)?,
            kw::FLOCK_PARALLEL => parse_flock_parallel(&ctx, a)?,
            kw::MAGELLAN => parse_magellan(&ctx, a)?,
            kw::CEREALBOX => parse_cerealbox(&ctx, a)?,
            _ => parse_dyna(&ctx, a)?,
        }
    };
    Ok(DeviceEntry {
        location: SourceLocation {
            file: file.to_owned(),
            line: line.number,
        },
        last_line: reader.last_number.max(line.number),
        keyword: tokens.keyword.to_owned(),
        args: a.iter().map(|s| (*s).to_owned()).collect(),
        config,
    })
}

/// Records the names `entry` defines; fails if one is already taken.
fn claim_names(
    taken: &mut HashMap<String, (usize, String)>,
    entry: &DeviceEntry,
) -> Result<(), ConfigError> {
    let names = entry.config.device_names();
    for (i, name) in names.iter().enumerate() {
        let earlier = taken
            .get(*name)
            .map(|(line, kw)| format!("{kw} at line {line}"))
            .or_else(|| {
                names[..i]
                    .contains(name)
                    .then(|| "this same entry".to_owned())
            });
        if let Some(earlier) = earlier {
            return Err(ConfigError::at_line(
                ConfigErrorKind::DuplicateName,
                &entry.location.file,
                entry.location.line,
                format!(
                    "{}: device name '{name}' is already used by {earlier}; give every \
                     device its own name",
                    entry.keyword
                ),
            ));
        }
    }
    for name in names {
        taken.insert(
            name.to_owned(),
            (entry.location.line, entry.keyword.clone()),
        );
    }
    Ok(())
}

/// The shared loop of [`parse_str`] and [`parse_str_lenient`].
fn parse_all(text: &str, file: &str, stop_at_first_error: bool) -> ParseReport {
    let mut report = ParseReport::default();
    let mut taken = HashMap::new();
    let mut reader = Reader::new(text, file);
    while let Some(next) = reader.next_raw() {
        let result = next.and_then(|line| match classify_line(line.text) {
            LineClass::Entry(tokens) => {
                let entry = parse_entry(file, line, &tokens, &mut reader)?;
                claim_names(&mut taken, &entry)?;
                Ok(Some(entry))
            }
            LineClass::Short | LineClass::Comment => Ok(None),
        });
        match result {
            Ok(Some(entry)) => report.entries.push(entry),
            Ok(None) => {}
            Err(e) => {
                report.errors.push(e);
                if stop_at_first_error {
                    break;
                }
            }
        }
    }
    report
}

/// Parses `vrpn.cfg` text; `file_name` is used in locations and messages.
///
/// Stops at the first malformed entry, like C++ `vrpn_server` without `-warn`. Unknown
/// keywords are returned as [`DeviceConfig::Unknown`] entries for the caller to refuse (C++
/// default) or skip with a warning (`-warn`), see [`DeviceEntry::unknown_error`].
pub fn parse_str(text: &str, file_name: &str) -> Result<Vec<DeviceEntry>, ConfigError> {
    let mut report = parse_all(text, file_name, true);
    match report.errors.pop() {
        Some(e) => Err(e),
        None => Ok(report.entries),
    }
}

/// Parses `vrpn.cfg` text the way C++ `vrpn_server -warn` does: a malformed entry is recorded
/// in [`ParseReport::errors`] and skipped, and parsing resumes at the next unread line.
pub fn parse_str_lenient(text: &str, file_name: &str) -> ParseReport {
    parse_all(text, file_name, false)
}

/// Reads a configuration file as UTF-8 text; errors name the file (and the line of the first
/// invalid byte).
pub fn read_config_text(path: &Path) -> Result<String, ConfigError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| {
        ConfigError::whole_file(
            ConfigErrorKind::Io,
            &file,
            format!("cannot read configuration file: {e}"),
        )
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let good = &bytes[..e.utf8_error().valid_up_to()];
        let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = good.len() - good.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1) + 1;
        let byte = bytes.get(good.len()).copied().unwrap_or_default();
        ConfigError::at_line(
            ConfigErrorKind::NotUtf8,
            &file,
            line,
            format!(
                "the file is not UTF-8 text (byte 0x{byte:02X} at column {column}); save it as \
                 UTF-8 or plain ASCII"
            ),
        )
    })
}

/// Reads and parses a `vrpn.cfg` file with [`parse_str`]'s rules; the path names the file in
/// messages.
pub fn parse_file(path: &Path) -> Result<Vec<DeviceEntry>, ConfigError> {
    let text = read_config_text(path)?;
    parse_str(&text, &path.display().to_string())
}

/// Reads and parses a `vrpn.cfg` file with [`parse_str_lenient`]'s rules (`-warn`). Only an
/// unreadable file is an error.
pub fn parse_file_lenient(path: &Path) -> Result<ParseReport, ConfigError> {
    let text = read_config_text(path)?;
    Ok(parse_str_lenient(&text, &path.display().to_string()))
}

// ---------------------------------------------------------------------------------------------
// vrpn_Tracker.cfg
// ---------------------------------------------------------------------------------------------

/// Default name of the per-tracker transform file, looked up in the working directory.
pub const TRACKER_CFG_FILE: &str = "vrpn_Tracker.cfg";

/// A rigid transform: translation then rotation quaternion `(x, y, z, w)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidTransform {
    /// Translation x, y, z.
    pub translation: [f32; 3],
    /// Rotation quaternion x, y, z, w.
    pub rotation: [f32; 4],
}

impl RigidTransform {
    /// No translation, no rotation.
    pub const IDENTITY: RigidTransform = RigidTransform {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
}

impl Default for RigidTransform {
    /// [`RigidTransform::IDENTITY`].
    fn default() -> Self {
        RigidTransform::IDENTITY
    }
}

/// The unit-to-sensor transform of one sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorTransform {
    /// Sensor index.
    pub sensor: u32,
    /// Unit-to-sensor transform.
    pub unit2sensor: RigidTransform,
}

/// One tracker's entry in `vrpn_Tracker.cfg` (CONFIG.md §6): what it answers to To_Room,
/// Unit_To_Sensor and Workspace requests.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerTransforms {
    /// Tracker-to-room transform.
    pub tracker2room: RigidTransform,
    /// Workspace minimum corner x, y, z.
    pub workspace_min: [f32; 3],
    /// Workspace maximum corner x, y, z.
    pub workspace_max: [f32; 3],
    /// Sensor count K from the file (trackers such as NULL override it with their own).
    pub num_sensors: u32,
    /// The K unit-to-sensor entries, in file order.
    pub unit2sensor: Vec<SensorTransform>,
}

impl Default for TrackerTransforms {
    /// What a tracker uses without a file: identities, workspace ±0.5, one sensor.
    fn default() -> Self {
        TrackerTransforms {
            tracker2room: RigidTransform::IDENTITY,
            workspace_min: [-0.5; 3],
            workspace_max: [0.5; 3],
            num_sensors: 1,
            unit2sensor: Vec::new(),
        }
    }
}

impl TrackerTransforms {
    /// The unit-to-sensor transform of `sensor` (the last entry for it), identity if none.
    pub fn unit2sensor_for(&self, sensor: u32) -> RigidTransform {
        self.unit2sensor
            .iter()
            .rev()
            .find(|s| s.sensor == sensor)
            .map_or(RigidTransform::IDENTITY, |s| s.unit2sensor)
    }
}

/// Whether `line` begins with `name` immediately followed by a whitespace character.
fn begins_with_name(line: &str, name: &str) -> bool {
    line.strip_prefix(name)
        .and_then(|rest| rest.chars().next())
        .is_some_and(is_c_space)
}

/// Reads the next line of a tracker entry and parses `N` floats from it.
fn tracker_floats<const N: usize>(
    ctx: &Ctx<'_>,
    reader: &mut Reader<'_>,
    what: &str,
    fields: [&str; N],
) -> Result<[f32; N], ConfigError> {
    let line = reader.block_line(ctx, &format!("its {what} line"))?;
    let here = ctx.at(line.number);
    let t = c_tokens(line.text);
    if t.len() < N {
        return Err(here.err(
            ConfigErrorKind::BadBlockLine,
            format!(
                "{what} line needs {N} numbers ({}), found {}",
                fields.join(" "),
                t.len()
            ),
        ));
    }
    let mut out = [0.0; N];
    for (i, v) in out.iter_mut().enumerate() {
        *v = f32_field(&here, &format!("{what} {}", fields[i]), t[i])?;
    }
    Ok(out)
}

/// Reads the next line of a tracker entry as one whole number in `0..=max`.
fn tracker_count(
    ctx: &Ctx<'_>,
    reader: &mut Reader<'_>,
    what: &str,
    max: u32,
) -> Result<u32, ConfigError> {
    let line = reader.block_line(ctx, &format!("its {what} line"))?;
    let here = ctx.at(line.number);
    match c_tokens(line.text).first() {
        Some(tok) => uint_in(&here, what, tok, 0, max),
        None => Err(here.err(
            ConfigErrorKind::BadBlockLine,
            format!("{what} line is empty; expected a whole number"),
        )),
    }
}

/// Reads one `vrpn_Tracker.cfg` unit-to-sensor entry (3 lines).
fn sensor_entry(ctx: &Ctx<'_>, reader: &mut Reader<'_>) -> Result<SensorTransform, ConfigError> {
    let sensor = tracker_count(ctx, reader, "sensor index", MAX_TRACKER_SENSORS - 1)?;
    let translation = tracker_floats(
        ctx,
        reader,
        &format!("sensor {sensor} unit-to-sensor translation"),
        ["x", "y", "z"],
    )?;
    let rotation = tracker_floats(
        ctx,
        reader,
        &format!("sensor {sensor} unit-to-sensor quaternion"),
        ["x", "y", "z", "w"],
    )?;
    Ok(SensorTransform {
        sensor,
        unit2sensor: RigidTransform {
            translation,
            rotation,
        },
    })
}

/// Finds and parses the entry for `tracker_name` (its full name, `@host` included for a
/// client) in `vrpn_Tracker.cfg` text.
///
/// An absent name is a [`ConfigErrorKind::TrackerNotFound`] error (C++ prints "Found config
/// file vrpn_Tracker.cfg, but cannot read info for NAME" and keeps its defaults; a caller
/// wanting that behaviour uses [`TrackerTransforms::default`]). Unlike C++, which silently
/// stops at a malformed unit-to-sensor entry, every malformed or missing line is an error.
pub fn parse_tracker_cfg(
    text: &str,
    file_name: &str,
    tracker_name: &str,
) -> Result<TrackerTransforms, ConfigError> {
    let mut reader = Reader::new(text, file_name);
    let header = loop {
        match reader.next_raw() {
            Some(Ok(line)) if begins_with_name(line.text, tracker_name) => break line,
            Some(Ok(_)) => {}
            Some(Err(e)) => return Err(e),
            None => {
                return Err(ConfigError::at_line(
                    ConfigErrorKind::TrackerNotFound,
                    file_name,
                    reader.last_number,
                    format!(
                        "no entry for tracker '{tracker_name}' (a line starting with the name \
                         followed by a blank); it keeps the default transforms"
                    ),
                ))
            }
        }
    };
    let ctx = Ctx::new(
        file_name,
        header.number,
        format!("tracker '{tracker_name}'"),
    );
    let t2r_pos = tracker_floats(
        &ctx,
        &mut reader,
        "tracker-to-room translation",
        ["x", "y", "z"],
    )?;
    let t2r_quat = tracker_floats(
        &ctx,
        &mut reader,
        "tracker-to-room quaternion",
        ["x", "y", "z", "w"],
    )?;
    let workspace = tracker_floats(
        &ctx,
        &mut reader,
        "workspace",
        ["min_x", "min_y", "min_z", "max_x", "max_y", "max_z"],
    )?;
    let num_sensors = tracker_count(&ctx, &mut reader, "sensor count", MAX_TRACKER_SENSORS)?;
    let mut unit2sensor = Vec::new();
    for _ in 0..num_sensors {
        unit2sensor.push(sensor_entry(&ctx, &mut reader)?);
    }
    Ok(TrackerTransforms {
        tracker2room: RigidTransform {
            translation: t2r_pos,
            rotation: t2r_quat,
        },
        workspace_min: [workspace[0], workspace[1], workspace[2]],
        workspace_max: [workspace[3], workspace[4], workspace[5]],
        num_sensors,
        unit2sensor,
    })
}

/// Loads `tracker_name`'s entry from a `vrpn_Tracker.cfg` file. A missing file is `Ok(None)`
/// (silent, as in C++); other read failures and parse problems are errors.
pub fn load_tracker_cfg(
    path: &Path,
    tracker_name: &str,
) -> Result<Option<TrackerTransforms>, ConfigError> {
    if !path.exists() {
        return Ok(None);
    }
    let text = read_config_text(path)?;
    parse_tracker_cfg(&text, &path.display().to_string(), tracker_name).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ctx() -> Ctx<'static> {
        Ctx::new("t.cfg", 7, "kw")
    }

    #[test]
    fn short_and_comment_lines() {
        assert_eq!(classify_line(""), LineClass::Short);
        assert_eq!(classify_line("\n"), LineClass::Short);
        assert_eq!(classify_line("x\n"), LineClass::Short);
        assert_eq!(classify_line("\r\n"), LineClass::Short);
        assert_eq!(classify_line("# comment\n"), LineClass::Comment);
        assert_eq!(classify_line(" \t #x\n"), LineClass::Comment);
    }

    #[test]
    fn keyword_and_args() {
        let LineClass::Entry(t) = classify_line("  vrpn_Tracker_NULL\tT0  2 60.0 # c\r\n") else {
            panic!("not an entry");
        };
        assert_eq!(t.keyword, "vrpn_Tracker_NULL");
        assert!(t.matchable);
        assert_eq!(t.args, ["T0", "2", "60.0", "#", "c"]);
    }

    #[test]
    fn keyword_alone_is_not_matchable() {
        let LineClass::Entry(t) = classify_line("vrpn_Tracker_NULL\n") else {
            panic!("not an entry");
        };
        assert_eq!(t.keyword, "vrpn_Tracker_NULL");
        assert!(!t.matchable);
        assert!(t.args.is_empty());
        // At the end of a file without newline the token matches, as in C++.
        let LineClass::Entry(t) = classify_line("vrpn_Tracker_NULL") else {
            panic!("not an entry");
        };
        assert!(t.matchable);
    }

    #[test]
    fn blank_only_line_is_an_entry_with_empty_keyword() {
        let LineClass::Entry(t) = classify_line("   \n") else {
            panic!("not an entry");
        };
        assert_eq!(t.keyword, "");
        assert!(!t.matchable);
    }

    #[test]
    fn c_tokens_split_on_all_c_whitespace() {
        assert_eq!(c_tokens(" a\tb\x0bc\x0cd\re\n"), ["a", "b", "c", "d", "e"]);
        assert!(c_tokens(" \t\r\n").is_empty());
    }

    #[test]
    fn from_token_keeps_inner_spacing() {
        assert_eq!(from_token(" a  5   hello   world \r\n", 2), "hello   world");
        assert_eq!(from_token(" a 5\n", 2), "");
    }

    #[test]
    fn integers() {
        let c = ctx();
        assert_eq!(int_in(&c, "n", "+5", 0, 9), Ok(5));
        let e = int_in(&c, "n", "2.5", 0, 9).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.cfg:7: kw: n must be a whole number, found '2.5'"
        );
        let e = int_in(&c, "n", "10", 0, 9).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.cfg:7: kw: n must be between 0 and 9, found 10"
        );
        assert_eq!(e.kind(), ConfigErrorKind::OutOfRange);
        let e = int_in(&c, "n", "99999999999999999999", 0, 9).unwrap_err();
        assert_eq!(e.kind(), ConfigErrorKind::OutOfRange);
    }

    #[test]
    fn floats_are_f32_and_finite() {
        let c = ctx();
        assert_eq!(f32_field(&c, "r", "0.1"), Ok(0.1f32));
        assert_eq!(f32_field(&c, "r", ".5"), Ok(0.5));
        assert_eq!(f32_field(&c, "r", "1e2"), Ok(100.0));
        let e = f32_field(&c, "r", "60Hz").unwrap_err();
        assert_eq!(e.message(), "kw: r must be a number, found '60Hz'");
        let e = f32_field(&c, "r", "nan").unwrap_err();
        assert_eq!(e.message(), "kw: r must be a finite number, found 'nan'");
        let e = f32_field(&c, "r", "1e39").unwrap_err();
        assert_eq!(e.kind(), ConfigErrorKind::OutOfRange);
        let e = positive(&c, "rate", "0").unwrap_err();
        assert_eq!(e.message(), "kw: rate must be greater than 0, found 0");
        assert_eq!(non_negative(&c, "rate", "0"), Ok(0.0));
    }

    #[test]
    fn baud_rates() {
        let c = ctx();
        assert_eq!(baud(&c, "115200"), Ok(115200));
        let e = baud(&c, "9601").unwrap_err();
        assert!(e.message().ends_with("found 9601"), "{e}");
    }

    #[test]
    fn device_refs() {
        assert_eq!(DeviceRef::parse("*M0"), Ok(DeviceRef::Local("M0".into())));
        assert_eq!(
            DeviceRef::parse("M0@host:3884"),
            Ok(DeviceRef::Remote("M0@host:3884".into()))
        );
        assert!(DeviceRef::parse("*").is_err());
        assert!(DeviceRef::parse("@host").is_err());
        assert!(DeviceRef::parse("M0@").is_err());
        assert!(DeviceRef::parse("*M0@host").is_err());
        let e = DeviceRef::parse("M0").unwrap_err();
        assert!(e.contains("*M0") && e.contains("M0@host"), "{e}");
        assert_eq!(DeviceRef::Local("M0".into()).to_string(), "*M0");
        assert_eq!(DeviceRef::Local("M0".into()).name(), "M0");
        let c = ctx();
        assert_eq!(device_ref(&c, "d", "NULL", true), Ok(None));
        assert!(device_ref(&c, "d", "NULL", false).is_err());
    }

    #[test]
    fn names() {
        let c = ctx();
        assert!(device_name(&c, "name", "a@b").is_err());
        assert!(device_name(&c, "name", &"n".repeat(MAX_NAME_LEN)).is_ok());
        assert!(device_name(&c, "name", &"n".repeat(MAX_NAME_LEN + 1)).is_err());
    }

    #[test]
    fn continuation_split() {
        assert_eq!(split_continuation("a b \\"), ("a b ", Some('\\')));
        assert_eq!(split_continuation("a b/"), ("a b", Some('/')));
        assert_eq!(split_continuation("a b /\r"), ("a b /\r", None));
        assert_eq!(split_continuation(""), ("", None));
    }

    #[test]
    fn hemispheres_and_axes() {
        assert_eq!(Hemisphere::parse("-X"), Some(Hemisphere::NegX));
        assert_eq!(Hemisphere::parse("z"), None);
        assert_eq!(Axis::from_keyword("RY"), Some(Axis::RY));
        assert_eq!(Axis::from_keyword("ry"), None);
        assert!(Axis::ALL.iter().enumerate().all(|(i, a)| a.index() == i));
    }

    #[test]
    fn known_keywords_are_distinct() {
        for (i, k) in KNOWN_KEYWORDS.iter().enumerate() {
            assert!(!KNOWN_KEYWORDS[..i].contains(k), "{k} twice");
        }
    }

    #[test]
    fn unknown_hints() {
        assert!(unknown_message("vrpn_tracker_null").contains("did you mean vrpn_Tracker_NULL"));
        assert!(unknown_message("vrpn_Tracker_IS900").contains("IS900time"));
        assert!(unknown_message("\u{feff}vrpn_Tracker_NULL").contains("byte-order mark"));
        assert_eq!(unknown_message("vrpn_Foo"), "unknown device type vrpn_Foo");
        assert!(unknown_message("vrpn_Joylin").contains("carriage return"));
        let entries = parse_str("vrpn_Joylin\rJ0 /dev/input/js0\n", "x").unwrap();
        assert!(entries[0].unknown_error().is_some());
    }

    #[test]
    fn tracker_name_prefix() {
        assert!(begins_with_name("Tracker0 x\n", "Tracker0"));
        assert!(begins_with_name("Tracker0\n", "Tracker0"));
        assert!(!begins_with_name("Tracker01\n", "Tracker0"));
        assert!(!begins_with_name("Tracker0", "Tracker0"));
    }

    #[test]
    fn reset_steps() {
        let c = ctx();
        assert_eq!(reset_step(&c, "*5"), Ok(ResetStep::Pause(5)));
        assert_eq!(reset_step(&c, "MCe"), Ok(ResetStep::Command("MCe".into())));
        assert!(reset_step(&c, "*x").is_err());
    }

    #[test]
    fn no_panic_on_odd_bytes() {
        for text in [
            "\u{0}\u{0}\u{0}\n",
            "vrpn_Tracker_Fastrak\\",
            "vrpn_Tracker_Fastrak a b 9600 \\",
            "vrpn_Tracker_Fastrak a b 9600 /\n/\n",
            "vrpn_Tracker_AnalogFly a 1 absolute",
            "vrpn_Tracker_ButtonFly a 1\n\n",
            "\u{feff}\u{feff}\u{feff}",
            "vrpn_Text_Example é 1 ü",
        ] {
            let _ = parse_str_lenient(text, "x");
            let _ = parse_tracker_cfg(text, "x", "a");
        }
    }
}
