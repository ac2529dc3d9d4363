//! One parsed `vrpn.cfg` entry: the device's configuration (from its driver), where it came
//! from, and the names and interfaces it serves; entries whose keyword no driver serves.

use std::collections::HashMap;
use std::fmt;

use crate::config::{ConfigError, ConfigErrorKind, SourceLocation};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::drivers::REGISTRY;
use crate::error::Error;

/// The entry of a keyword no driver serves. C++ `vrpn_server` stops on it by default and skips
/// it with `-warn`; see [`DeviceEntry::unknown_error`]. Serves nothing; building it fails.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownDevice {
    /// The first token of the line (empty for a line of only blanks).
    pub keyword: String,
    /// The remaining tokens.
    pub args: Vec<String>,
}

impl DeviceSpec for UnknownDevice {
    fn name(&self) -> &str {
        ""
    }

    fn served(&self) -> Vec<Served<'_>> {
        Vec::new()
    }

    fn device_names(&self) -> Vec<&str> {
        Vec::new()
    }

    fn build(&self, _cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Err(Error::Unsupported("an unknown device type cannot be built"))
    }
}

/// Two entries (or two station devices of one entry) that serve the same interface under the
/// same name. C++ `vrpn_server` does not check names and runs both, their reports interleaved
/// under one sender; so does this server, after warning with this value's text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NameClash {
    /// The shared name.
    pub name: String,
    /// The interface both serve.
    pub interface: Interface,
    /// The earlier entry.
    pub first: SourceLocation,
    /// The earlier entry's keyword.
    pub first_keyword: String,
    /// The later entry (the same as `first` when one entry serves the interface twice).
    pub second: SourceLocation,
    /// The later entry's keyword.
    pub second_keyword: String,
}

impl fmt::Display for NameClash {
    /// `FILE:LINE: KEYWORD: 'NAME' is already a tracker (KEYWORD at line N); both run and
    /// their reports interleave under one name, as in C++ VRPN: give each its own name`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let earlier = if self.first == self.second {
            "earlier in this same entry".to_owned()
        } else if self.first.file == self.second.file {
            format!("{} at line {}", self.first_keyword, self.first.line)
        } else {
            format!("{} at {}", self.first_keyword, self.first)
        };
        write!(
            f,
            "{}: {}: device name '{}' is already a {} ({earlier}); both run and their reports \
             interleave under one name, as in C++ VRPN: give each its own name",
            self.second, self.second_keyword, self.name, self.interface
        )
    }
}

/// Finds every pair of entries that serve the same interface under the same name, in file
/// order of the later one. Distinct interfaces under one name are fine and not reported.
pub fn name_clashes(entries: &[DeviceEntry]) -> Vec<NameClash> {
    let mut first_by: HashMap<Served<'_>, &DeviceEntry> = HashMap::new();
    let mut clashes = Vec::new();
    for entry in entries {
        for served in entry.config.served() {
            match first_by.get(&served) {
                Some(first) => clashes.push(NameClash {
                    name: served.name.to_owned(),
                    interface: served.interface,
                    first: first.location.clone(),
                    first_keyword: first.keyword.clone(),
                    second: entry.location.clone(),
                    second_keyword: entry.keyword.clone(),
                }),
                None => {
                    first_by.insert(served, entry);
                }
            }
        }
    }
    clashes
}

/// One entry of `vrpn.cfg`.
#[derive(Debug)]
pub struct DeviceEntry {
    /// Where the entry starts.
    pub location: SourceLocation,
    /// Last line the entry used (differs from `location.line` for multi-line entries).
    pub last_line: usize,
    /// The keyword as written (for an [`UnknownDevice`], the unrecognised one).
    pub keyword: String,
    /// The tokens after the keyword on the first line.
    pub args: Vec<String>,
    /// The parsed configuration: the driver's own type, reached with
    /// [`spec`](Self::spec), or an [`UnknownDevice`].
    pub config: Box<dyn DeviceSpec>,
}

impl DeviceEntry {
    /// The configuration as the driver's type `T`, if it is one.
    pub fn spec<T: DeviceSpec>(&self) -> Option<&T> {
        self.config.downcast_ref::<T>()
    }

    /// True for the entry of a keyword no driver serves.
    pub fn is_unknown(&self) -> bool {
        self.spec::<UnknownDevice>().is_some()
    }

    /// For an [`UnknownDevice`] entry, the error to report: C++ `vrpn_server` stops with
    /// "Unknown Device" by default, and with `-warn` prints it and skips the line (print this
    /// error followed by `, skipped`). `None` for known entries.
    pub fn unknown_error(&self) -> Option<ConfigError> {
        let UnknownDevice { keyword, .. } = self.spec::<UnknownDevice>()?;
        let message = unknown_message(keyword);
        Some(ConfigError::at_line(
            ConfigErrorKind::UnknownDevice,
            &self.location.file,
            self.location.line,
            message,
        ))
    }
}

/// Every keyword a driver serves, in registry order.
pub fn known_keywords() -> impl Iterator<Item = &'static str> {
    REGISTRY.iter().flat_map(|d| d.keywords.iter().copied())
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
    if known_keywords().any(|k| k == keyword) {
        return format!(
            "{base}: a character other than a space or tab (such as a carriage return) follows \
             the keyword; separate it from its arguments with spaces or tabs"
        );
    }
    let hint = REGISTRY
        .iter()
        .flat_map(|d| d.hints.iter())
        .find(|h| h.keyword == keyword);
    if let Some(hint) = hint {
        return format!("{base}: {}", hint.text);
    }
    if let Some(known) = known_keywords().find(|k| k.eq_ignore_ascii_case(keyword)) {
        return format!("{base}: keywords are case-sensitive, did you mean {known}?");
    }
    base
}

/// Result of [`parse_str_lenient`](super::parse_str_lenient): the entries that parsed and the
/// problems with the rest.
#[derive(Debug, Default)]
pub struct ParseReport {
    /// Entries that parsed, in file order (unknown ones included).
    pub entries: Vec<DeviceEntry>,
    /// One error per skipped entry or line, in file order.
    pub errors: Vec<ConfigError>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server::config::parse_str;

    #[test]
    fn unknown_hints() {
        assert!(unknown_message("vrpn_tracker_null").contains("did you mean vrpn_Tracker_NULL"));
        // A driver's hint for a keyword it does not serve is given as the explanation.
        let hint = REGISTRY.iter().flat_map(|d| d.hints.iter()).next().unwrap();
        assert!(unknown_message(hint.keyword).ends_with(hint.text));
        assert!(unknown_message("\u{feff}vrpn_Tracker_NULL").contains("byte-order mark"));
        assert_eq!(unknown_message("vrpn_Foo"), "unknown device type vrpn_Foo");
        assert!(unknown_message("vrpn_Tracker_NULL").contains("carriage return"));
        let entries = parse_str("vrpn_Tracker_NULL\rT0 1 60\n", "x").unwrap();
        assert!(entries[0].unknown_error().is_some());
    }
}
