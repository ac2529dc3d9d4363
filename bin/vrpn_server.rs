//! vrpn_server: serves the devices of a vrpn.cfg file, with the C++ command line.

#[path = "common/output.rs"]
mod output;
#[path = "common/signals.rs"]
mod signals;

use std::path::Path;
use std::process::ExitCode;

use vrpn::devices::base::set_print_threshold;
use vrpn::driver::DeviceStatus;
use vrpn::server::config::{self, DeviceEntry};
use vrpn::server::options::USAGE;
use vrpn::server::{build_devices_in, parse_args, BuildNote, ServerCommand, ServerLoop};
use vrpn::{Connection, Limits, TextSeverity};

use output::{errln, outln};

const PROGRAM: &str = "vrpn_server";

fn main() -> ExitCode {
    let opts = match parse_args(std::env::args().skip(1)) {
        Ok(ServerCommand::Serve(o)) => o,
        Ok(ServerCommand::Help) => {
            outln!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Ok(ServerCommand::Version) => {
            outln!("{PROGRAM} {}", env!("CARGO_PKG_VERSION"));
            return ExitCode::SUCCESS;
        }
        Err(msg) => {
            errln!("{PROGRAM}: {msg}");
            return ExitCode::from(2);
        }
    };
    let tree = match &opts.device_root {
        Some(root) => vrpn::hid::DeviceTree::under(root),
        None => vrpn::hid::DeviceTree::system(),
    };
    if opts.list_devices {
        let listed = vrpn::hid::list::list(&tree, vrpn::drivers::SUGGESTERS);
        outln!("{}", vrpn::hid::list::render(&listed).trim_end());
        return ExitCode::SUCCESS;
    }
    signals::install();
    // 255 clients on the UDP path hold three sockets each.
    vrpn::server::raise_descriptor_limit();
    if let Some(shift) = opts.clock_shift {
        vrpn::time::shift_wall_clock(shift);
        errln!("{PROGRAM}: stamping messages {shift:+} s off this host's clock (-clockshift)");
    }
    if opts.verbose {
        set_print_threshold(TextSeverity::Normal);
    }
    let Some(entries) = read_config(&opts.config, opts.warn_only) else {
        return ExitCode::from(1);
    };
    // One name may serve several interfaces; the same interface twice under one name runs
    // both (as C++ does) but deserves a warning.
    for clash in config::name_clashes(&entries) {
        errln!("{PROGRAM}: warning: {clash}");
    }
    let limits = Limits {
        callback_to_named_address: opts.callback_to_named_address,
        ..Limits::default()
    };
    let conn = match Connection::server_with_limits(opts.nic, opts.port, limits) {
        Ok(c) => c,
        Err(e) => {
            errln!("{PROGRAM}: {e}");
            return ExitCode::from(1);
        }
    };
    // Logs open before the devices register, so their descriptions are logged (as C++).
    for (path, incoming) in [(&opts.log_in, true), (&opts.log_out, false)] {
        if let Some(path) = path {
            let (r, option) = if incoming {
                (conn.log_incoming(path), "-li")
            } else {
                (conn.log_outgoing(path), "-lo")
            };
            if let Err(e) = r {
                errln!("{PROGRAM}: {option}: {e}");
                return ExitCode::from(1);
            }
        }
    }
    if let Some(dir) = &opts.log_dir {
        match vrpn::log::LogFolder::new(dir) {
            Ok(folder) => conn.set_remote_log_folder(Some(folder)),
            Err(e) => {
                errln!("{PROGRAM}: -logdir {e}");
                return ExitCode::from(1);
            }
        }
    }
    let verbose = opts.verbose;
    // A device's port problems (cannot open it, lost it) and recoveries, once per change.
    // Under -v the device's own text about a problem is shown as it is sent (`show_texts`):
    // the status line would say the same thing a second time.
    let status: vrpn::driver::StatusSink =
        std::rc::Rc::new(move |name: &str, status: &DeviceStatus| {
            let told_by_text = matches!(
                status,
                DeviceStatus::CannotOpen { .. } | DeviceStatus::Lost { .. }
            );
            if !(verbose && told_by_text) {
                errln!("{PROGRAM}: {name}: {status}");
            }
        });
    let cx = vrpn::driver::BuildContext::with_status(&conn, status).with_device_tree(tree);
    let devices = build_devices_in(&entries, &cx, opts.warn_only, |note| match note {
        BuildNote::Opened { entry, name } if verbose => {
            errln!(
                "{PROGRAM}: opening {}: {name} ({})",
                entry.keyword,
                entry.location
            );
        }
        BuildNote::Opened { .. } => {}
        BuildNote::Skipped { error, .. } => errln!("{PROGRAM}: {error}, skipped"),
    });
    let mut devices = match devices {
        Ok(d) => d,
        Err(e) => {
            errln!("{PROGRAM}: {e}");
            return ExitCode::from(1);
        }
    };
    // Remote-controlled forwarding, as C++ vrpn_server runs it (off until -forwardports).
    let served = devices.len();
    match vrpn::forward::ForwarderServer::new(&conn) {
        Ok(forwarder) => {
            forwarder.set_nic(opts.nic);
            if let Some(ports) = &opts.forward_ports {
                forwarder.allow_ports(ports.clone());
            }
            devices.push(Box::new(forwarder));
        }
        Err(e) => errln!("{PROGRAM}: forwarding unavailable: {e}"),
    }
    // Diagnostics go to stderr, once each; standard output carries only the "serving" line
    // (scripts read the port from it). See "Output streams" in the README.
    conn.on_notice(move |n| {
        if verbose || n.severity >= vrpn::Severity::Warning {
            errln!("vrpn: {}", n.text)
        }
    });
    if verbose {
        if let Err(e) = show_texts(&conn) {
            errln!("{PROGRAM}: {e}");
            return ExitCode::from(1);
        }
    }
    let port = conn.local_port().unwrap_or(opts.port);
    let nic = opts
        .nic
        .map_or("all interfaces".to_string(), |n| n.to_string());
    if !opts.quiet {
        outln!(
            "{PROGRAM}: serving {served} device(s) from {} on port {port} ({nic})",
            opts.config
        );
    }
    let mut server = ServerLoop::new(conn, devices, opts.sleep);
    server.quit_after_last(opts.quit_after_last);
    server.flush_logs_every_pass(opts.flush_logs);
    // Until a signal, `-q` and the last client leaving, or standard output closing (as a Unix
    // tool ends when its reader goes away).
    let result = loop {
        if signals::stop_requested() || output::closed() {
            break Ok(());
        }
        match server.pass() {
            Ok(true) => {}
            Ok(false) => break Ok(()),
            Err(e) => break Err(e),
        }
        if let Err(e) = server.wait() {
            break Err(e);
        }
    };
    // Close the logs (DISCONNECT entry, flush) before exiting.
    if let Err(e) = server.connection().close_logs() {
        errln!("{PROGRAM}: {e}");
    }
    if let Err(e) = result {
        errln!("{PROGRAM}: {e}");
        return ExitCode::from(1);
    }
    match output::failure() {
        Some(e) => {
            errln!("{PROGRAM}: writing output: {e}");
            ExitCode::from(1)
        }
        None => ExitCode::SUCCESS,
    }
}

/// `-v`: prints every text message the devices send (and any a client sends) on stderr, one
/// line each, as it is sent. The devices' texts go to the clients anyway; a server sees its
/// own outgoing messages through the connection's local delivery.
fn show_texts(conn: &Connection) -> Result<(), vrpn::Error> {
    use vrpn::wire::payload::text::{TextMessage, TEXT_MESSAGE};
    let text_type = conn.register_type(TEXT_MESSAGE)?;
    conn.register_handler(text_type, vrpn::SenderFilter::Any, |m| {
        let Ok(t) = TextMessage::decode(m.payload) else {
            return;
        };
        let sender = m.connection().sender_name(m.sender).unwrap_or_default();
        let severity = match TextSeverity::from_code(t.severity) {
            TextSeverity::Normal => "message",
            TextSeverity::Warning => "warning",
            TextSeverity::Error => "error",
            TextSeverity::Other(_) => "text",
        };
        errln!(
            "{PROGRAM}: {severity} from {sender} (level {}): {}",
            t.level,
            String::from_utf8_lossy(t.text)
        );
    });
    Ok(())
}

/// Reads the configuration file. Without `-warn` the first bad entry is fatal (`None`, after
/// printing it); with `-warn` bad entries are printed and skipped, as C++ does.
fn read_config(path: &str, warn_only: bool) -> Option<Vec<DeviceEntry>> {
    let path = Path::new(path);
    if !warn_only {
        return config::parse_file(path)
            .map_err(|e| errln!("{PROGRAM}: {e}"))
            .ok();
    }
    match config::parse_file_lenient(path) {
        Ok(report) => {
            for e in &report.errors {
                errln!("{PROGRAM}: {e}, skipped");
            }
            Some(report.entries)
        }
        Err(e) => {
            errln!("{PROGRAM}: {e}");
            None
        }
    }
}
