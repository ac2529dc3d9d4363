//! The default printer: where a connection's notices and devices' warning texts go when the
//! application registered nothing for them.
//!
//! C++ VRPN prints device texts to stdout as `VRPN Warning` followed by a line
//! ` (LEVEL) from SENDER: TEXT`, unasked. This crate prints nothing unless nothing else is
//! registered, and then only where [`set_text_printer`] says: by default one line on stderr.
//! An application that wants no output at all chooses [`TextPrinter::Off`]; one that wants
//! the notices registers [`Connection::on_notice`](super::Connection::on_notice).

use std::io::Write;
use std::sync::atomic::{AtomicU8, Ordering};

use super::Notice;
use crate::wire::payload::text::TextSeverity;

/// Where the default printer writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum TextPrinter {
    /// One line per text or notice on stderr (the default).
    Stderr,
    /// Device texts on stdout in C++'s two-line format; notices on stderr.
    CppStdout,
    /// Nothing.
    Off,
}

static PRINTER: AtomicU8 = AtomicU8::new(0);
static THRESHOLD: AtomicU8 = AtomicU8::new(1);

/// Chooses where the default printer writes, for the whole process.
pub fn set_text_printer(p: TextPrinter) {
    let v = match p {
        TextPrinter::Stderr => 0,
        TextPrinter::CppStdout => 1,
        TextPrinter::Off => 2,
    };
    PRINTER.store(v, Ordering::Relaxed);
}

fn printer() -> TextPrinter {
    match PRINTER.load(Ordering::Relaxed) {
        0 => TextPrinter::Stderr,
        1 => TextPrinter::CppStdout,
        _ => TextPrinter::Off,
    }
}

/// Sets the lowest severity of device texts the default printer shows (warnings by
/// default; `vrpn_server -v` shows everything).
pub fn set_print_threshold(severity: TextSeverity) {
    let v = match severity {
        TextSeverity::Normal => 0,
        TextSeverity::Warning => 1,
        TextSeverity::Error | TextSeverity::Other(_) => 2,
    };
    THRESHOLD.store(v, Ordering::Relaxed);
}

fn shown(severity: TextSeverity) -> bool {
    let v = match severity {
        TextSeverity::Normal => 0,
        TextSeverity::Warning => 1,
        TextSeverity::Error | TextSeverity::Other(_) => 2,
    };
    v >= THRESHOLD.load(Ordering::Relaxed)
}

/// Prints a notice nobody registered for. Write errors (a closed stderr) are ignored.
pub(crate) fn print_notice(n: &Notice) {
    if printer() == TextPrinter::Off {
        return;
    }
    let _ = writeln!(std::io::stderr(), "vrpn: {}", n.text);
}

/// Prints a device's text message nobody registered for.
pub(crate) fn print_text(sender: &str, severity: TextSeverity, level: u32, text: &str) {
    if !shown(severity) {
        return;
    }
    match printer() {
        TextPrinter::Off => {}
        TextPrinter::Stderr => {
            let what = match severity {
                TextSeverity::Normal => "message",
                TextSeverity::Warning => "warning",
                TextSeverity::Error => "error",
                TextSeverity::Other(_) => "text",
            };
            let _ = writeln!(
                std::io::stderr(),
                "vrpn: {what} from {sender} (level {level}): {text}"
            );
        }
        TextPrinter::CppStdout => {
            let _ = writeln!(
                std::io::stdout(),
                "{}\n ({level}) from {sender}: {text}",
                severity.heading()
            );
        }
    }
}
