//! vrpn_server: serves the devices of a vrpn.cfg file, with the C++ command line.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use vrpn::devices::base::set_print_threshold;
use vrpn::server::{build_devices, config, parse_args, ServerLoop};
use vrpn::{Connection, TextSeverity};

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: i32) {
    STOP.store(true, Ordering::Relaxed);
}

fn install_signal_handlers() {
    use nix::sys::signal::{sigaction, SaFlags, SigAction, SigHandler, SigSet, Signal};
    let action = SigAction::new(
        SigHandler::Handler(on_signal),
        SaFlags::empty(),
        SigSet::empty(),
    );
    for s in [Signal::SIGINT, Signal::SIGTERM] {
        // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
        unsafe {
            let _ = sigaction(s, &action);
        }
    }
}

fn main() {
    let opts = match parse_args(std::env::args().skip(1)) {
        Ok(o) => o,
        Err(msg) => {
            eprintln!("{msg}");
            std::process::exit(2);
        }
    };
    install_signal_handlers();
    if opts.verbose {
        set_print_threshold(TextSeverity::Normal);
    }
    let entries = match config::parse_file(Path::new(&opts.config)) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("vrpn_server: {e}");
            std::process::exit(1);
        }
    };
    let conn = match Connection::server(opts.nic, opts.port) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("vrpn_server: {e}");
            std::process::exit(1);
        }
    };
    // Logs open before the devices register, so their descriptions are logged (as C++).
    for (path, incoming) in [(&opts.log_in, true), (&opts.log_out, false)] {
        if let Some(path) = path {
            let r = if incoming {
                conn.log_incoming(path)
            } else {
                conn.log_outgoing(path)
            };
            if let Err(e) = r {
                eprintln!("vrpn_server: {path}: {e}");
                std::process::exit(1);
            }
        }
    }
    let devices = match build_devices(&entries, &conn, opts.warn_only, opts.verbose) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("vrpn_server: {e}");
            std::process::exit(1);
        }
    };
    if opts.verbose {
        conn.on_notice(|n| println!("vrpn: {}", n.text));
    } else {
        conn.on_notice(|n| {
            if n.severity >= vrpn::Severity::Warning {
                eprintln!("vrpn: {}", n.text)
            }
        });
    }
    let port = conn.local_port().unwrap_or(opts.port);
    let nic = opts
        .nic
        .map_or("all interfaces".to_string(), |n| n.to_string());
    println!(
        "vrpn_server: serving {} device(s) from {} on port {port} ({nic})",
        devices.len(),
        opts.config
    );
    let mut server = ServerLoop::new(conn, devices, opts.sleep);
    server.quit_after_last(opts.quit_after_last);
    server.flush_logs_every_pass(opts.flush_logs);
    let result = server.run(&STOP);
    // Close the logs (DISCONNECT entry, flush) before exiting.
    if let Err(e) = server.connection().close_logs() {
        eprintln!("vrpn_server: {e}");
    }
    if let Err(e) = result {
        eprintln!("vrpn_server: {e}");
        std::process::exit(1);
    }
}
