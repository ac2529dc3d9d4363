//! vrpn_monitor: a live web page of VRPN devices. Trackers in a 3D view with their numbers,
//! buttons, analogs, dials, text messages and each connection's state, updated 30 times a
//! second over server-sent events. The VRPN loop runs on the main thread and waits without
//! spinning on every connection's descriptor at once; one more thread answers HTTP.

#[path = "common/cli.rs"]
mod cli;
#[path = "monitor/http.rs"]
mod http;
#[path = "monitor/model.rs"]
mod model;
#[path = "common/output.rs"]
mod output;
#[path = "common/signals.rs"]
mod signals;

use std::net::SocketAddr;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use vrpn::{Connection, ConnectionState, TimeVal};

use model::Device;
use output::{errln, outln};

const PROGRAM: &str = "vrpn_monitor";

const USAGE: &str = "usage: vrpn_monitor [--http ADDR:PORT] [--allow-remote] DEVICE@HOST[:PORT]...
       vrpn_monitor [--http ADDR:PORT] [--allow-remote] --list HOST[:PORT]
       vrpn_monitor --help | --version

Serves a live page of the devices at http://ADDR:PORT/ (default 127.0.0.1:8080): trackers
in a 3D view with position, orientation, rate and report age, buttons, analogs, dials, text
messages, and each connection's state and reconnections.

  --http ADDR:PORT  where to serve the page (port 0 picks a free one; the address is printed)
  --allow-remote    allow ADDR to be other than a loopback address. The page has no
                    authentication: anyone who reaches the port sees the devices
  --list HOST[:PORT]
                    monitor every device the server at HOST announces (also those it adds)
  --seconds S       stop after S seconds
  -h, --help        print this help
  --version         print the version

Exit status: 0 when stopped (Ctrl-C, --seconds), 1 when the page cannot be served, 2 on a
usage error.";

/// Snapshots per second sent to the pages.
const SNAPSHOTS_PER_SEC: u32 = 30;

struct Options {
    http: SocketAddr,
    allow_remote: bool,
    list: Option<String>,
    devices: Vec<String>,
    seconds: Option<f64>,
}

enum Command {
    Run(Options),
    Help,
    Version,
}

fn parse_options() -> Result<Command, lexopt::Error> {
    use lexopt::prelude::*;
    let mut parser = lexopt::Parser::from_env();
    let mut o = Options {
        http: SocketAddr::from(([127, 0, 0, 1], 8080)),
        allow_remote: false,
        list: None,
        devices: Vec::new(),
        seconds: None,
    };
    while let Some(arg) = parser.next()? {
        match arg {
            Short('h') | Long("help") => return Ok(Command::Help),
            Long("version") => return Ok(Command::Version),
            Long("http") => o.http = cli::value(&mut parser, "--http", "ADDR:PORT")?,
            Long("allow-remote") => o.allow_remote = true,
            Long("list") => o.list = Some(parser.value()?.string()?),
            Long("seconds") => {
                let s: f64 = cli::value(&mut parser, "--seconds", "a number of seconds")?;
                if !(s.is_finite() && s > 0.0) {
                    return Err(format!("--seconds needs a positive number, got {s}").into());
                }
                o.seconds = Some(s);
            }
            Value(v) => o.devices.push(v.string()?),
            _ => return Err(arg.unexpected()),
        }
    }
    if o.list.is_some() && !o.devices.is_empty() {
        return Err("--list takes no device names".into());
    }
    if o.list.is_none() && o.devices.is_empty() {
        return Err("name at least one DEVICE@HOST, or --list HOST".into());
    }
    if !o.http.ip().is_loopback() && !o.allow_remote {
        return Err(format!(
            "--http {} is not a loopback address; the page has no authentication, so serving \
             another interface needs --allow-remote as well",
            o.http
        )
        .into());
    }
    Ok(Command::Run(o))
}

/// The monitored devices, the connections they use (one per location), and the discovery
/// of `--list`.
struct Devices {
    devices: Vec<Device>,
    connections: Vec<Connection>,
    /// `--list`: the server's location and the connection its device names come from.
    discover: Option<(String, Connection)>,
}

impl Devices {
    fn add(&mut self, name: &str) -> Result<(), vrpn::Error> {
        let d = Device::open(name)?;
        if !self.connections.iter().any(|c| c.same_as(d.connection())) {
            self.connections.push(d.connection().clone());
        }
        self.devices.push(d);
        Ok(())
    }

    /// Opens the devices the listed server announces that are not monitored yet.
    fn discover(&mut self) {
        let Some((location, conn)) = &self.discover else {
            return;
        };
        if conn.state() != ConnectionState::Connected {
            return;
        }
        let location = location.clone();
        for s in conn.peer_devices() {
            if s == PROGRAM || self.devices.iter().any(|d| d.name() == s) {
                continue;
            }
            if let Err(e) = self.add(&format!("{s}@{location}")) {
                errln!("{PROGRAM}: {s}: {e}");
            }
        }
    }

    fn snapshot(&self) -> String {
        let now = TimeVal::now();
        let mono = Instant::now();
        let devices: Vec<serde_json::Value> =
            self.devices.iter().map(|d| d.snapshot(now, mono)).collect();
        let listing = self.discover.as_ref().map(|(l, c)| {
            serde_json::json!({"location": l, "state": format!("{:?}", c.state()).to_lowercase()})
        });
        serde_json::json!({"time": now.as_secs_f64(), "list": listing, "devices": devices})
            .to_string()
    }
}

fn run(o: Options) -> u8 {
    let server = match tiny_http::Server::http(o.http) {
        Ok(s) => s,
        Err(e) => {
            errln!("{PROGRAM}: cannot serve on {}: {e}", o.http);
            return 1;
        }
    };
    let addr = server
        .server_addr()
        .to_ip()
        .map_or_else(|| o.http.to_string(), |a| a.to_string());
    let mut devices = Devices {
        devices: Vec::new(),
        connections: Vec::new(),
        discover: None,
    };
    for name in &o.devices {
        if let Err(e) = devices.add(name) {
            errln!("{PROGRAM}: {e}");
            return cli::USAGE_STATUS;
        }
    }
    if let Some(location) = &o.list {
        match Connection::open(&format!("{PROGRAM}@{location}")) {
            Ok(c) => {
                devices.connections.push(c.clone());
                devices.discover = Some((location.clone(), c));
            }
            Err(e) => {
                errln!("{PROGRAM}: {e}");
                return cli::USAGE_STATUS;
            }
        }
    }
    outln!("{PROGRAM}: serving http://{addr}/ (no authentication)");

    let feed = http::Feed::default();
    let stop = Arc::new(AtomicBool::new(false));
    let web = http::spawn(server, feed.clone(), stop.clone());
    let interval = Duration::from_secs(1) / SNAPSHOTS_PER_SEC;
    let start = Instant::now();
    // More seconds than a schedule holds (10^9) is as good as forever.
    let end = o.seconds.map(|s| {
        let d = vrpn::time::checked_duration(s).unwrap_or(vrpn::time::MAX_PERIOD);
        vrpn::time::instant_after(start, d)
    });
    let mut next = start;
    while !signals::stop_requested()
        && !output::closed()
        && !end.is_some_and(|e| Instant::now() >= e)
    {
        for c in &devices.connections {
            if let Err(e) = c.mainloop() {
                errln!("{PROGRAM}: {e}");
            }
        }
        devices.discover();
        let now = Instant::now();
        if now >= next {
            feed.publish(devices.snapshot());
            next = (next + interval).max(now);
        }
        // Sleep until a socket of any connection is readable, a connection has timed work,
        // or the next snapshot is due.
        let waiters: Vec<vrpn::Waiter> = devices
            .connections
            .iter()
            .map(|c| c.prepare_wait(None))
            .collect();
        if let Err(e) = vrpn::net::block_any(&waiters, next.saturating_duration_since(now)) {
            errln!("{PROGRAM}: waiting: {e}");
            break;
        }
    }
    stop.store(true, Ordering::Relaxed);
    let _ = web.join();
    0
}

fn main() -> ExitCode {
    let status = match parse_options() {
        Ok(Command::Help) => {
            outln!("{USAGE}");
            0
        }
        Ok(Command::Version) => {
            outln!("{}", cli::version(PROGRAM));
            0
        }
        Ok(Command::Run(o)) => {
            signals::install();
            vrpn::connection::set_text_printer(vrpn::connection::TextPrinter::Off);
            run(o)
        }
        Err(e) => {
            errln!("{}", cli::usage_error(PROGRAM, &cli::describe(&e)));
            cli::USAGE_STATUS
        }
    };
    match output::failure() {
        Some(e) => {
            errln!("{PROGRAM}: writing output: {e}");
            ExitCode::from(1)
        }
        None => ExitCode::from(status),
    }
}
