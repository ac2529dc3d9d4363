//! Where an entry or a problem is, and the error type every configuration parser returns.

use std::fmt;

/// Where an entry or a problem is in a configuration file.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct SourceLocation {
    /// The file name as given to the parser (a path for [`parse_file`](crate::server::config::parse_file)).
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
    /// A line is longer than [`MAX_LINE_LEN`](super::MAX_LINE_LEN).
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
    /// Two entries define the same device name. The parser no longer reports this: one name
    /// may serve several interfaces, and a repeated interface is only warned about (see
    /// [`crate::server::config::name_clashes`]). Kept so that existing matches still compile.
    DuplicateName,
    /// A multi-line entry is not closed before the end of the file.
    UnclosedBlock,
    /// A line inside a multi-line entry is malformed.
    BadBlockLine,
    /// The keyword is not one we know (see
    /// [`DeviceEntry::unknown_error`](crate::server::config::DeviceEntry::unknown_error)).
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

/// Error context: file, line and what is being parsed (e.g. `vrpn_Tracker_NULL`); its
/// [`err`](Self::err) makes a [`ConfigError`] that names all three.
#[derive(Clone, Debug)]
pub struct Ctx<'a> {
    /// The file name, as given to the parser.
    pub file: &'a str,
    /// The 1-based line.
    pub line: usize,
    /// What is being parsed (the keyword, or the keyword and the device name in a block);
    /// every message starts with it.
    pub what: String,
}

impl<'a> Ctx<'a> {
    /// The context of `what` at `line` of `file`.
    pub fn new(file: &'a str, line: usize, what: impl Into<String>) -> Self {
        Ctx {
            file,
            line,
            what: what.into(),
        }
    }

    /// The same context at another line (inside a block).
    pub fn at(&self, line: usize) -> Ctx<'a> {
        Ctx::new(self.file, line, self.what.clone())
    }

    /// An error here: `FILE:LINE: WHAT: message`.
    pub fn err(&self, kind: ConfigErrorKind, message: impl fmt::Display) -> ConfigError {
        ConfigError::at_line(
            kind,
            self.file,
            self.line,
            format!("{}: {message}", self.what),
        )
    }
}
