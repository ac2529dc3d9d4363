//! Standard output for a program whose reader may leave early (`vrpn_print_devices | head`).
//!
//! Rust ignores SIGPIPE, so writing to a closed pipe is an error rather than the signal that
//! silently ends a C program; `println!` turns that error into a panic. The programs write
//! through [`line()`] instead: once the reader has gone, [`closed`] turns true, further output is
//! dropped, and the program's loop ends as if interrupted, with its usual exit status. Other
//! write failures (a full disk) also stop the output and are kept for [`failure`].

use std::fmt;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

static CLOSED: AtomicBool = AtomicBool::new(false);
static FAILURE: Mutex<Option<io::Error>> = Mutex::new(None);

/// Writes `args` and a newline to standard output and flushes it. Returns false, writing
/// nothing, once the output is closed.
pub fn line(args: fmt::Arguments<'_>) -> bool {
    if closed() {
        return false;
    }
    let mut out = io::stdout().lock();
    let written = out
        .write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
    match written {
        Ok(()) => true,
        Err(e) => {
            stop(e);
            false
        }
    }
}

/// Records a write error on standard output (from a program's own buffered writer): output is
/// closed from now on.
pub fn stop(e: io::Error) {
    CLOSED.store(true, Ordering::Relaxed);
    if e.kind() != io::ErrorKind::BrokenPipe {
        if let Ok(mut failure) = FAILURE.lock() {
            failure.get_or_insert(e);
        }
    }
}

/// True once standard output can take no more (its reader has gone, or a write failed).
pub fn closed() -> bool {
    CLOSED.load(Ordering::Relaxed)
}

/// The write error that closed the output, unless it was only the reader leaving (a broken
/// pipe, which is no failure of the program).
pub fn failure() -> Option<io::Error> {
    FAILURE.lock().ok().and_then(|mut f| f.take())
}

/// `println!` that never panics: see [`line()`].
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::output::line(format_args!($($arg)*))
    };
}

/// `eprintln!` that never panics: a message nobody can read is dropped.
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

pub(crate) use {errln, outln};
