//! Entries that continue over several lines the way C++ VRPN's Polhemus-style trackers read
//! them: a line whose very last character is `\` is followed by a reset command line, one
//! whose last character is `/` by a line describing a device attached to the tracker (a
//! stylus, a wand, another wireless sensor). A blank after the character ends the entry, as in
//! C++, which looks at the character just before the newline.
//!
//! Reset command lines are sent to the tracker as they are, each followed by a carriage
//! return; a line starting with `*` is a pause of that many whole seconds instead. The last
//! reset command line may end in `/` to go on with device lines.

use super::error::{ConfigError, ConfigErrorKind, Ctx};
use super::fields::uint_in;
use super::lines::{c_tokens, is_c_space};
use super::ConfigLine;

/// Most characters the reset commands of one entry may hold together (C++'s buffer).
pub const MAX_RESET_COMMANDS: usize = 2048;

/// Longest pause a reset command line may ask for, in seconds.
pub const MAX_PAUSE_SECONDS: u32 = 3600;

/// One line of a tracker's extra reset sequence (`\` lines).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ResetStep {
    /// `*N`: wait N seconds.
    Pause(u32),
    /// A command sent to the tracker, followed by a carriage return (not stored here).
    Command(String),
}

/// Splits a trailing continuation character (`\` or `/`, the very last character before the
/// newline) off a line's content.
pub fn split_continuation(content: &str) -> (&str, Option<char>) {
    match content.chars().last() {
        Some(c @ ('\\' | '/')) => (&content[..content.len() - 1], Some(c)),
        _ => (content, None),
    }
}

/// The first line of an entry: its arguments (a lone `\` or `/` at the end is not one) and the
/// continuation character it ends in.
pub fn head<'t>(line: &ConfigLine<'t, '_>) -> (Vec<&'t str>, Option<char>) {
    let rest = line.rest();
    let (head, cont) = split_continuation(rest.strip_suffix('\n').unwrap_or(rest));
    (c_tokens(head), cont)
}

/// Reads the reset command lines that follow a line ending in `cont` (none unless it is `\`).
/// Returns them and the continuation character the last one ends in (`/` when device lines
/// follow).
pub fn reset_steps(
    line: &mut ConfigLine<'_, '_>,
    mut cont: Option<char>,
) -> Result<(Vec<ResetStep>, Option<char>), ConfigError> {
    let ctx = line.ctx().clone();
    let mut steps = Vec::new();
    let mut total = 0usize;
    while cont == Some('\\') {
        let next = line.block_line("the reset command promised by the trailing '\\'")?;
        let (body, c) = split_continuation(next.content());
        let here = ctx.at(next.number);
        total += body.len() + 1;
        if total > MAX_RESET_COMMANDS {
            return Err(here.err(
                ConfigErrorKind::BadBlockLine,
                format!("reset commands exceed {MAX_RESET_COMMANDS} characters in total"),
            ));
        }
        steps.push(reset_step(&here, body)?);
        cont = c;
    }
    Ok((steps, cont))
}

fn reset_step(ctx: &Ctx<'_>, body: &str) -> Result<ResetStep, ConfigError> {
    let Some(secs) = body.strip_prefix('*') else {
        return Ok(ResetStep::Command(body.to_owned()));
    };
    let secs = secs.trim_matches(is_c_space);
    uint_in(
        ctx,
        "reset pause (*N, in seconds)",
        secs,
        0,
        MAX_PAUSE_SECONDS,
    )
    .map(ResetStep::Pause)
}

/// Reads the device lines that follow a line ending in `cont` (none unless it is `/`): each
/// line's tokens go to `parse` with the line's context; a line ending in `/` is followed by
/// another. `what` names the lines expected, for the error at the end of the file.
pub fn device_lines<T>(
    line: &mut ConfigLine<'_, '_>,
    mut cont: Option<char>,
    what: &str,
    mut parse: impl FnMut(&Ctx<'_>, &[&str]) -> Result<T, ConfigError>,
) -> Result<Vec<T>, ConfigError> {
    let ctx = line.ctx().clone();
    let mut out = Vec::new();
    while cont == Some('/') {
        let next = line.block_line(&format!("the {what} line promised by the trailing '/'"))?;
        let (body, c) = split_continuation(next.content());
        out.push(parse(&ctx.at(next.number), &c_tokens(body))?);
        cont = c;
    }
    Ok(out)
}

/// The bytes a reset command is sent as: its text and a carriage return.
pub fn command_bytes(command: &str, out: &mut Vec<u8>) {
    out.extend_from_slice(command.as_bytes());
    out.push(b'\r');
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn continuation_is_the_very_last_character() {
        assert_eq!(split_continuation("a b \\"), ("a b ", Some('\\')));
        assert_eq!(split_continuation("a b /"), ("a b ", Some('/')));
        assert_eq!(split_continuation("a b / "), ("a b / ", None));
        assert_eq!(split_continuation(""), ("", None));
    }
}
