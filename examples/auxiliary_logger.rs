//! Asks an auxiliary logging server to log for a while, then to stop (what C++
//! `run_auxiliary_logger` does, with all four names).
//!
//! `cargo run --example auxiliary_logger -- Logger0@localhost LOCAL_IN LOCAL_OUT REMOTE_IN
//! REMOTE_OUT SECONDS` — use `""` for a log you do not want. Exits 0 when the server reported
//! the names asked for, then four empty names after the stop.

use std::cell::RefCell;
use std::process::ExitCode;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::{AuxLoggerRemote, LogFiles, LoggingReport};

fn wait_for_report(
    logger: &AuxLoggerRemote,
    reports: &RefCell<Vec<LoggingReport>>,
    seen: usize,
) -> Option<LoggingReport> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(5) {
        logger.mainloop().ok()?;
        if let Some(r) = reports.borrow().get(seen) {
            return Some(r.clone());
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    None
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 6 {
        eprintln!(
            "usage: auxiliary_logger Logger@host LOCAL_IN LOCAL_OUT REMOTE_IN REMOTE_OUT SECONDS"
        );
        return ExitCode::from(2);
    }
    let files = LogFiles::new(&args[1], &args[2], &args[3], &args[4]);
    let seconds: f64 = args[5].parse().unwrap_or(1.0);
    let logger = match AuxLoggerRemote::new(&args[0]) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(1);
        }
    };
    let reports = Rc::new(RefCell::new(Vec::new()));
    let r = reports.clone();
    logger.on_report(move |rep| {
        println!(
            "log report: '{}' '{}' '{}' '{}'",
            rep.files.local_in, rep.files.local_out, rep.files.remote_in, rep.files.remote_out
        );
        r.borrow_mut().push(rep.clone());
    });
    let start = Instant::now();
    while !logger.connection().connected() && start.elapsed() < Duration::from_secs(5) {
        let _ = logger.mainloop();
        std::thread::sleep(Duration::from_millis(1));
    }
    let mut ok = logger.request_logging(&files).is_ok()
        && wait_for_report(&logger, &reports, 0).is_some_and(|r| r.files == files);
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs_f64(seconds) {
        let _ = logger.mainloop();
        std::thread::sleep(Duration::from_millis(1));
    }
    ok &= logger.request_status().is_ok()
        && wait_for_report(&logger, &reports, 1).is_some_and(|r| r.files == files);
    ok &= logger.stop_logging().is_ok()
        && wait_for_report(&logger, &reports, 2).is_some_and(|r| r.files.is_empty());
    println!("{}", if ok { "Success!" } else { "Failed." });
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
