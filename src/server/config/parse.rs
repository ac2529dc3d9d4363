//! The top level of `vrpn.cfg`: reading a file, handing each entry to the driver that serves
//! its keyword, strict (default) and lenient (`-warn`) parsing.

use std::path::Path;

use super::entry::{DeviceEntry, ParseReport, UnknownDevice};
use crate::config::lines::{classify_line, EntryTokens, LineClass, RawLine, Reader};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, SourceLocation};
use crate::driver::registry::{find, DeviceSpec};
use crate::drivers::REGISTRY;

/// Parses the entry whose first line is `line`, reading block lines from `reader`.
fn parse_entry<'t>(
    file: &'t str,
    line: RawLine<'t>,
    tokens: EntryTokens<'t>,
    reader: &mut Reader<'t>,
) -> Result<DeviceEntry, ConfigError> {
    let keyword = tokens.keyword.to_owned();
    let args: Vec<String> = tokens.args.iter().map(|s| (*s).to_owned()).collect();
    let driver = find(REGISTRY, tokens.keyword);
    let config: Box<dyn DeviceSpec> = match driver {
        // C++ prints "Unknown Device" for it. A known keyword alone on its line is also
        // "unknown" to C++; it falls through to the argument-count error instead.
        Some(driver) if tokens.matchable || args.is_empty() => {
            (driver.parse)(&mut ConfigLine::new(file, line.number, tokens, reader))?
        }
        _ => Box::new(UnknownDevice {
            keyword: keyword.clone(),
            args: args.clone(),
        }),
    };
    Ok(DeviceEntry {
        location: SourceLocation {
            file: file.to_owned(),
            line: line.number,
        },
        last_line: reader.last_number.max(line.number),
        keyword,
        args,
        config,
    })
}

/// The shared loop of [`parse_str`] and [`parse_str_lenient`].
fn parse_all(text: &str, file: &str, stop_at_first_error: bool) -> ParseReport {
    let mut report = ParseReport::default();
    let mut reader = Reader::new(text, file);
    while let Some(next) = reader.next_raw() {
        let result = next.and_then(|line| match classify_line(line.text) {
            LineClass::Entry(tokens) => parse_entry(file, line, tokens, &mut reader).map(Some),
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
/// keywords are returned as [`UnknownDevice`] entries for the caller to refuse (C++ default)
/// or skip with a warning (`-warn`), see [`DeviceEntry::unknown_error`].
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server::config::parse_tracker_cfg;

    #[test]
    fn no_panic_on_odd_bytes() {
        for text in [
            "\u{0}\u{0}\u{0}\n",
            "vrpn_Tracker_NULL\\",
            "vrpn_Tracker_NULL a 1 60 \\",
            "vrpn_Tracker_NULL a 1 60 /\n/\n",
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
