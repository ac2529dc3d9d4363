//! vrpn_ping: measures the user-level round trip (ping to pong) to any VRPN server, C++ or ours.

#[path = "common/cli.rs"]
mod cli;
#[path = "common/output.rs"]
mod output;

use std::cell::Cell;
use std::process::ExitCode;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::base::{PING_MESSAGE, PONG_MESSAGE};
use vrpn::wire::class;
use vrpn::{Connection, DeviceName, SenderFilter, TimeVal};

use output::{errln, outln};

const PROGRAM: &str = "vrpn_ping";

/// How long to wait for the connection, and then for each pong, before giving up.
const GIVE_UP: Duration = Duration::from_secs(2);

const USAGE: &str = "usage: vrpn_ping [-n COUNT] DEVICE@HOST[:PORT]
       vrpn_ping --help | --version
  Sends COUNT pings (default 1000) to DEVICE and prints the round-trip p50/p99/max in µs.
  The server answers pings only for devices it has, so DEVICE must exist there.
  Gives up (exit status 1) when no server answers within 2 s, or a ping within 2 s.
  -n, --count COUNT  number of pings, at least 1 (default 1000)
  -h, --help         print this help
  --version          print the version";

/// What the command line asks for.
enum Command {
    Ping { name: String, count: usize },
    Help,
    Version,
}

fn parse_args() -> Result<Command, lexopt::Error> {
    use lexopt::prelude::*;
    let mut parser = lexopt::Parser::from_env();
    let mut count = 1000usize;
    let mut name = None;
    while let Some(arg) = parser.next()? {
        match arg {
            Short('n') | Long("count") => {
                count = cli::value(&mut parser, "-n", "a positive count")?;
                if count == 0 {
                    return Err("-n needs a positive count, got 0".into());
                }
            }
            Short('h') | Long("help") => return Ok(Command::Help),
            Long("version") => return Ok(Command::Version),
            Value(v) if name.is_none() => name = Some(v.string()?),
            _ => return Err(arg.unexpected()),
        }
    }
    match name {
        Some(name) => Ok(Command::Ping { name, count }),
        None => Err("name the DEVICE@HOST[:PORT] to ping".into()),
    }
}

fn main() -> ExitCode {
    let status = match parse_args() {
        Ok(Command::Help) => {
            outln!("{USAGE}");
            0
        }
        Ok(Command::Version) => {
            outln!("{}", cli::version(PROGRAM));
            0
        }
        Ok(Command::Ping { name, count }) => match run(&name, count) {
            Ok(mut rtts) => {
                rtts.sort_unstable_by(f64::total_cmp);
                let pct = |p: f64| rtts[((rtts.len() - 1) as f64 * p).round() as usize];
                outln!(
                    "{} pings to {name}: p50 {:.1} µs  p99 {:.1} µs  max {:.1} µs",
                    rtts.len(),
                    pct(0.5),
                    pct(0.99),
                    rtts[rtts.len() - 1]
                );
                0
            }
            Err(e) => {
                errln!("{PROGRAM}: {e}");
                1
            }
        },
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

fn run(name: &str, count: usize) -> Result<Vec<f64>, String> {
    let parsed = DeviceName::parse(name).map_err(|e| e.to_string())?;
    let conn = Connection::open_location(&parsed).map_err(|e| e.to_string())?;
    let sender = conn
        .register_sender(&parsed.device)
        .map_err(|e| e.to_string())?;
    let ping = conn
        .register_type(PING_MESSAGE)
        .map_err(|e| e.to_string())?;
    let pong = conn
        .register_type(PONG_MESSAGE)
        .map_err(|e| e.to_string())?;
    let pongs = Rc::new(Cell::new(0u64));
    let p = pongs.clone();
    conn.register_handler(pong, SenderFilter::Only(sender), move |_| {
        p.set(p.get() + 1)
    });
    // The connection's notices (no server, not VRPN, …) explain a failure: keep the latest
    // for the message instead of printing each as it comes.
    let last_notice = Rc::new(std::cell::RefCell::new(None::<String>));
    let ln = last_notice.clone();
    let notices = conn.on_notice(move |n| *ln.borrow_mut() = Some(n.text.clone()));
    let start = Instant::now();
    while !conn.connected() {
        if start.elapsed() > GIVE_UP {
            let why = last_notice
                .borrow()
                .as_deref()
                .map(|t| format!(" ({})", t.trim_end_matches("; will keep retrying")))
                .unwrap_or_default();
            return Err(format!(
                "no connection to {name} within {} s{why}; is a VRPN server running there?",
                GIVE_UP.as_secs()
            ));
        }
        conn.mainloop().map_err(|e| e.to_string())?;
        let _ = conn.wait(Duration::from_millis(5));
    }
    conn.remove_handler(notices);
    let mut rtts = Vec::with_capacity(count);
    for i in 0..count {
        let before = pongs.get();
        let t0 = Instant::now();
        conn.pack_message(TimeVal::now(), ping, sender, &[], class::RELIABLE)
            .map_err(|e| e.to_string())?;
        loop {
            conn.mainloop().map_err(|e| e.to_string())?;
            if pongs.get() > before {
                break;
            }
            if t0.elapsed() > GIVE_UP {
                return Err(format!(
                    "ping {i} got no pong within {} s: does {} exist on that server?",
                    GIVE_UP.as_secs(),
                    parsed.device
                ));
            }
        }
        rtts.push(t0.elapsed().as_secs_f64() * 1e6);
    }
    Ok(rtts)
}
