//! The tokenizer: physical lines, C++ `vrpn_server`'s line classes and `isspace` tokens.

use super::error::{ConfigError, ConfigErrorKind, Ctx};
use super::MAX_LINE_LEN;

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
pub struct RawLine<'a> {
    /// 1-based line number.
    pub number: usize,
    /// The text, newline included.
    pub text: &'a str,
}

impl<'a> RawLine<'a> {
    /// The text without its newline.
    pub fn content(&self) -> &'a str {
        self.text.strip_suffix('\n').unwrap_or(self.text)
    }
}

/// Reads physical lines, enforcing the line-length limit.
pub(crate) struct Reader<'a> {
    file: &'a str,
    lines: std::iter::Enumerate<std::str::SplitInclusive<'a, char>>,
    pub(crate) last_number: usize,
}

impl<'a> Reader<'a> {
    pub fn new(text: &'a str, file: &'a str) -> Self {
        Reader {
            file,
            lines: text.split_inclusive('\n').enumerate(),
            last_number: 0,
        }
    }

    pub fn next_raw(&mut self) -> Option<Result<RawLine<'a>, ConfigError>> {
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
    pub fn block_line(&mut self, ctx: &Ctx<'_>, closing: &str) -> Result<RawLine<'a>, ConfigError> {
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

/// The text of `rest` from its `n`th token (0-based) on, blanks around it removed.
pub fn from_token(rest: &str, n: usize) -> &str {
    let mut s = rest.trim_start_matches(is_c_space);
    for _ in 0..n {
        let end = s.find(is_c_space).unwrap_or(s.len());
        s = s[end..].trim_start_matches(is_c_space);
    }
    s.trim_end_matches(is_c_space)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
