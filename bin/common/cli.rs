//! Command-line conventions shared by the GNU-style programs (`vrpn_print_devices`, `vrpn_ping`,
//! `vrpn_log`), whose options are read with `lexopt`: one-line usage errors with exit status 2,
//! `--version`.

use std::str::FromStr;

/// Exit status of a usage error, as GNU tools use.
pub const USAGE_STATUS: u8 = 2;

/// The text `--version` prints.
pub fn version(program: &str) -> String {
    format!("{program} {}", env!("CARGO_PKG_VERSION"))
}

/// A parse error in words, without the program name.
pub fn describe(e: &lexopt::Error) -> String {
    use lexopt::Error::*;
    match e {
        MissingValue { option: Some(o) } => format!("{o} needs a value"),
        MissingValue { option: None } => "a value is missing".to_owned(),
        UnexpectedOption(o) => format!("unknown option {o}"),
        UnexpectedArgument(a) => format!("unexpected argument {a:?}"),
        UnexpectedValue { option, value } => format!("{option} takes no value (got {value:?})"),
        ParsingFailed { value, error } => format!("{value:?}: {error}"),
        NonUnicodeValue(v) => format!("argument {v:?} is not valid UTF-8"),
        Custom(e) => e.to_string(),
    }
}

/// The one-line message for a usage error: `PROGRAM: PROBLEM (see PROGRAM --help)`.
pub fn usage_error(program: &str, problem: &str) -> String {
    format!("{program}: {problem} (see {program} --help)")
}

/// Reads the value of `option` as a `T`; the error names the option and what it expects.
#[allow(dead_code)] // not every program has a typed option
pub fn value<T: FromStr>(
    parser: &mut lexopt::Parser,
    option: &str,
    expected: &str,
) -> Result<T, lexopt::Error> {
    let raw = parser.value()?;
    let text = raw.to_str().unwrap_or_default();
    text.parse()
        .map_err(|_| format!("{option} needs {expected}, got {raw:?}").into())
}

/// The command line with the C++ single-dash spellings of `long_names` (`-notracker`) turned
/// into their GNU form (`--notracker`), so that both spellings work and lexopt reads them.
#[allow(dead_code)] // not every program has C++ spellings
pub fn with_cpp_spellings(long_names: &[&str]) -> Vec<std::ffi::OsString> {
    std::env::args_os()
        .skip(1)
        .map(|a| match a.to_str() {
            Some(s)
                if s.starts_with('-') && !s.starts_with("--") && long_names.contains(&&s[1..]) =>
            {
                format!("-{s}").into()
            }
            _ => a,
        })
        .collect()
}
