//! One parsed `vrpn.cfg` entry: the device configuration by type, where it came from, and the
//! names and interfaces it serves.

use std::collections::HashMap;
use std::fmt;

use super::devices::{
    AnalogExample, ButtonExample, CerealBox, DialExample, Dyna, Flock, FlockParallel, Joylin,
    Magellan, TextExample, TrackerNull, TrackerSpin,
};
use super::error::{ConfigError, ConfigErrorKind, SourceLocation};
use super::fastrak::{Fastrak, InterSense, StationDevice};
use super::fly::{AnalogFly, ButtonFly};
use super::{kw, KNOWN_KEYWORDS};

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

    /// Every (name, interface) pair this entry serves, in the order the server creates them:
    /// the device's own interfaces under its name, then each station device's under the
    /// station's name (a Wand is a Button and an Analog, a Stylus or FTStylus a Button).
    /// Empty for [`DeviceConfig::Unknown`].
    ///
    /// Every device can also send text messages (warnings, errors) under its name; only
    /// `vrpn_Text_Example`, which exists to send them, counts as serving [`Interface::Text`].
    pub fn served(&self) -> Vec<Served<'_>> {
        use Interface::*;
        let own: &[Interface] = match self {
            DeviceConfig::TrackerNull(_)
            | DeviceConfig::TrackerSpin(_)
            | DeviceConfig::AnalogFly(_)
            | DeviceConfig::ButtonFly(_)
            | DeviceConfig::Fastrak(_)
            | DeviceConfig::InterSense(_)
            | DeviceConfig::Flock(_)
            | DeviceConfig::FlockParallel(_)
            | DeviceConfig::Dyna(_) => &[Tracker],
            DeviceConfig::ButtonExample(_) => &[Button],
            DeviceConfig::DialExample(_) => &[Dial],
            DeviceConfig::AnalogExample(_) => &[Analog],
            DeviceConfig::TextExample(_) => &[Text],
            DeviceConfig::Joylin(_) | DeviceConfig::Magellan(_) => &[Analog, Button],
            DeviceConfig::CerealBox(_) => &[Button, Analog, Dial],
            DeviceConfig::Unknown { .. } => &[],
        };
        let mut served: Vec<Served<'_>> = match self.name() {
            Some(name) => own
                .iter()
                .map(|&interface| Served { name, interface })
                .collect(),
            None => Vec::new(),
        };
        let stations = match self {
            DeviceConfig::Fastrak(d) => &d.stations[..],
            DeviceConfig::InterSense(d) => &d.stations[..],
            _ => &[],
        };
        for station in stations {
            let interfaces: &[Interface] = match station {
                StationDevice::Wand { .. } => &[Button, Analog],
                StationDevice::Stylus { .. } | StationDevice::FtStylus { .. } => &[Button],
            };
            served.extend(interfaces.iter().map(|&interface| Served {
                name: station.name(),
                interface,
            }));
        }
        served
    }
}

/// A VRPN device interface: what a client opens a remote of (`TrackerRemote`, `ButtonRemote`,
/// …) to read a device. One name may carry several interfaces, since each has its own message
/// types; two devices serving the same interface under one name send indistinguishable reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Interface {
    /// Poses, velocities and accelerations (`vrpn_Tracker`).
    Tracker,
    /// Button presses (`vrpn_Button`).
    Button,
    /// Analog channels (`vrpn_Analog`).
    Analog,
    /// Dial turns (`vrpn_Dial`).
    Dial,
    /// Text messages as the device's purpose (`vrpn_Text_Example`).
    Text,
}

impl Interface {
    /// The interface in lower case, as messages name it (`tracker`, `button`, …).
    pub fn label(self) -> &'static str {
        match self {
            Interface::Tracker => "tracker",
            Interface::Button => "button",
            Interface::Analog => "analog",
            Interface::Dial => "dial",
            Interface::Text => "text sender",
        }
    }
}

impl fmt::Display for Interface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// One interface an entry serves, and the name it serves it under.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Served<'a> {
    /// The device name clients open (`NAME@host`).
    pub name: &'a str,
    /// The interface.
    pub interface: Interface,
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

/// Result of [`parse_str_lenient`](super::parse_str_lenient): the entries that parsed and the problems with the rest.
#[derive(Clone, Debug, Default, PartialEq)]
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
        assert!(unknown_message("vrpn_Tracker_IS900").contains("IS900time"));
        assert!(unknown_message("\u{feff}vrpn_Tracker_NULL").contains("byte-order mark"));
        assert_eq!(unknown_message("vrpn_Foo"), "unknown device type vrpn_Foo");
        assert!(unknown_message("vrpn_Joylin").contains("carriage return"));
        let entries = parse_str("vrpn_Joylin\rJ0 /dev/input/js0\n", "x").unwrap();
        assert!(entries[0].unknown_error().is_some());
    }
}
