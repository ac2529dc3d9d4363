//! [`ConfigLine`]: one `vrpn.cfg` entry as a driver's parser sees it.

use super::error::{ConfigError, ConfigErrorKind, Ctx};
use super::fields;
use super::lines::{from_token, EntryTokens, RawLine, Reader};
use super::DeviceRef;

/// The entry a driver's parser is handed: the keyword's line split into tokens, the context
/// every error names (file, line, keyword), and the lines after it for entries that continue
/// over several lines.
///
/// The field methods take the argument's index (0 = the first token after the keyword) and
/// the field's name for messages; each returns a [`ConfigError`] reading
/// `FILE:LINE: KEYWORD: FIELD must …, found …`. Call [`need`](Self::need) first: a field
/// method given an index past the end reports a missing argument rather than panicking.
///
/// ```
/// # use vrpn::config::{ConfigLine, ConfigError};
/// /// `vrpn_Tracker_Example NAME PORT BAUD [fast]`
/// fn parse(line: &mut ConfigLine<'_, '_>) -> Result<(String, String, u32, bool), ConfigError> {
///     line.need(3, "name, port, baud, [fast]")?;
///     Ok((line.name(0)?, line.word(1)?.to_owned(), line.baud(2)?, line.arg(3) == Some("fast")))
/// }
/// ```
pub struct ConfigLine<'t, 'r> {
    ctx: Ctx<'t>,
    tokens: EntryTokens<'t>,
    reader: &'r mut Reader<'t>,
}

impl<'t, 'r> ConfigLine<'t, 'r> {
    pub(crate) fn new(
        file: &'t str,
        number: usize,
        tokens: EntryTokens<'t>,
        reader: &'r mut Reader<'t>,
    ) -> Self {
        ConfigLine {
            ctx: Ctx::new(file, number, tokens.keyword),
            tokens,
            reader,
        }
    }

    /// The keyword, as written.
    pub fn keyword(&self) -> &'t str {
        self.tokens.keyword
    }

    /// File, line and keyword, for the free functions of [`fields`] and for block contexts.
    pub fn ctx(&self) -> &Ctx<'t> {
        &self.ctx
    }

    /// The tokens after the keyword (split on C `isspace`, as `sscanf("%s")` reads them).
    pub fn args(&self) -> &[&'t str] {
        &self.tokens.args
    }

    /// Argument `i`, if the line has it.
    pub fn arg(&self, i: usize) -> Option<&'t str> {
        self.tokens.args.get(i).copied()
    }

    /// The text after the keyword, newline included (for entries whose last field is free
    /// text, or that look at the line's last character).
    pub fn rest(&self) -> &'t str {
        self.tokens.rest
    }

    /// The text from argument `n` on, with its inner spacing kept and blanks around it
    /// removed.
    pub fn text_from(&self, n: usize) -> &'t str {
        from_token(self.tokens.rest, n)
    }

    /// An error at this line: `FILE:LINE: KEYWORD: message`.
    pub fn err(&self, kind: ConfigErrorKind, message: impl std::fmt::Display) -> ConfigError {
        self.ctx.err(kind, message)
    }

    /// Fails unless the line has at least `min` arguments; `usage` names them all.
    pub fn need(&self, min: usize, usage: &str) -> Result<(), ConfigError> {
        fields::need(&self.ctx, self.args(), min, usage)
    }

    fn tok(&self, i: usize, field: &str) -> Result<&'t str, ConfigError> {
        self.arg(i).ok_or_else(|| {
            self.err(
                ConfigErrorKind::MissingArguments,
                format!("{field} (argument {}) is missing", i + 1),
            )
        })
    }

    /// Argument `i` as it is (a port path, a file name, a word).
    pub fn word(&self, i: usize) -> Result<&'t str, ConfigError> {
        self.tok(i, "an argument")
    }

    /// Argument `i` as the name the device publishes under (no `@`, not too long).
    pub fn name(&self, i: usize) -> Result<String, ConfigError> {
        fields::device_name(&self.ctx, "name", self.tok(i, "name")?)
    }

    /// Argument `i` as a whole number in `lo..=hi`.
    pub fn uint(&self, i: usize, field: &str, lo: u32, hi: u32) -> Result<u32, ConfigError> {
        fields::uint_in(&self.ctx, field, self.tok(i, field)?, lo, hi)
    }

    /// Argument `i` as any whole number a C `int` holds.
    pub fn int(&self, i: usize, field: &str) -> Result<i32, ConfigError> {
        fields::any_int(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a finite number, read as C++ reads `%f` (the nearest `f32`).
    pub fn f32(&self, i: usize, field: &str) -> Result<f32, ConfigError> {
        fields::f32_field(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a finite number, read as C++ reads `%lf`.
    pub fn f64(&self, i: usize, field: &str) -> Result<f64, ConfigError> {
        fields::f64_field(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a rate or period greater than 0.
    pub fn positive(&self, i: usize, field: &str) -> Result<f32, ConfigError> {
        fields::positive(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a number of 0 or more.
    pub fn non_negative(&self, i: usize, field: &str) -> Result<f32, ConfigError> {
        fields::non_negative(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a report rate per second: greater than 0 and at least one report per
    /// [`MAX_PERIOD`](crate::time::MAX_PERIOD), so that a schedule can hold it.
    pub fn rate(&self, i: usize, field: &str) -> Result<f32, ConfigError> {
        fields::rate(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a report rate that may also be 0 (see [`rate`](Self::rate)).
    pub fn rate_or_zero(&self, i: usize, field: &str) -> Result<f32, ConfigError> {
        fields::rate_or_zero(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a period in seconds: greater than 0, at most
    /// [`MAX_PERIOD`](crate::time::MAX_PERIOD).
    pub fn period(&self, i: usize, field: &str) -> Result<f32, ConfigError> {
        fields::period(&self.ctx, field, self.tok(i, field)?)
    }

    /// Argument `i` as a serial baud rate (one of [`BAUD_RATES`](super::BAUD_RATES)).
    pub fn baud(&self, i: usize) -> Result<u32, ConfigError> {
        fields::baud(&self.ctx, self.tok(i, "baud")?)
    }

    /// Argument `i` as a reference to another device (`*NAME` or `NAME@host`; `NULL` is
    /// `None` when `allow_null`).
    pub fn device_ref(
        &self,
        i: usize,
        field: &str,
        allow_null: bool,
    ) -> Result<Option<DeviceRef>, ConfigError> {
        fields::device_ref(&self.ctx, field, self.tok(i, field)?, allow_null)
    }

    /// The next line of a multi-line entry, read as it is (no comment or short-line
    /// filtering). The end of the file is an error saying the block needed `closing`.
    pub fn block_line(&mut self, closing: &str) -> Result<RawLine<'t>, ConfigError> {
        self.reader.block_line(&self.ctx, closing)
    }

    /// [`block_line`](Self::block_line) with another context for the error (a block names
    /// the device as well as the keyword).
    pub fn block_line_in(
        &mut self,
        ctx: &Ctx<'_>,
        closing: &str,
    ) -> Result<RawLine<'t>, ConfigError> {
        self.reader.block_line(ctx, closing)
    }
}
