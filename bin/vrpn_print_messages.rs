//! vrpn_print_messages: prints every message a connection (a server, or a log replayed with
//! `file:`) delivers, with its time, sender, type and length, in C++'s line format. Unlike
//! C++, it writes no temporary log file and works on log files too.

#[path = "common/cli.rs"]
mod cli;
#[path = "common/output.rs"]
mod output;
#[path = "common/signals.rs"]
mod signals;

use std::cell::RefCell;
use std::process::ExitCode;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::{Connection, SenderFilter};

use output::{errln, outln};

const PROGRAM: &str = "vrpn_print_messages";

const USAGE: &str = "usage: vrpn_print_messages [--json] [--seconds S] CONNECTION
       vrpn_print_messages --help | --version
  CONNECTION   what to listen to: HOST[:PORT], tcp://HOST:PORT, Device@HOST[:PORT], or
               file:LOG.vrpn (a log, replayed at its own pace; the program ends at its end)
  --json       one JSON object per message: time, sender, type, length
  --seconds S  exit after S seconds (default: run until interrupted)
  -h, --help   print this help
  --version    print the version
Each line: Time: SECONDS:MICROSECONDS, Sender: NAME, Type NAME, Length BYTES";

struct Options {
    json: bool,
    seconds: Option<f64>,
    location: String,
}

enum Command {
    Print(Options),
    Help,
    Version,
}

fn parse_args() -> Result<Command, lexopt::Error> {
    use lexopt::prelude::*;
    let mut parser = lexopt::Parser::from_env();
    let mut json = false;
    let mut seconds = None;
    let mut location = None;
    while let Some(arg) = parser.next()? {
        match arg {
            Long("json") => json = true,
            Long("seconds") => {
                let s: f64 = cli::value(&mut parser, "--seconds", "a number of seconds")?;
                if !(s.is_finite() && s >= 0.0) {
                    return Err(format!("--seconds needs a number of seconds, got {s}").into());
                }
                seconds = Some(s);
            }
            Short('h') | Long("help") => return Ok(Command::Help),
            Long("version") => return Ok(Command::Version),
            Value(v) if location.is_none() => location = Some(v.string()?),
            _ => return Err(arg.unexpected()),
        }
    }
    let location = location.ok_or("name the CONNECTION to listen to")?;
    Ok(Command::Print(Options {
        json,
        seconds,
        location,
    }))
}

/// Names of the connection's ids, looked up once each (the lines are printed from them).
#[derive(Default)]
struct NameCache {
    senders: Vec<Option<Rc<str>>>,
    types: Vec<Option<Rc<str>>>,
}

impl NameCache {
    fn get(
        table: &mut Vec<Option<Rc<str>>>,
        id: i32,
        look_up: impl FnOnce() -> Option<String>,
        unknown: &str,
    ) -> Rc<str> {
        let Ok(i) = usize::try_from(id) else {
            return unknown.into();
        };
        if table.len() <= i {
            table.resize(i + 1, None);
        }
        table[i]
            .get_or_insert_with(|| look_up().unwrap_or_else(|| unknown.into()).into())
            .clone()
    }
}

fn json_line(time: vrpn::TimeVal, sender: &str, type_name: &str, len: usize) -> String {
    let text = |s: &str| serde_json::to_string(s).expect("a string serialises");
    format!(
        "{{\"time\":{},\"sender\":{},\"type\":{},\"length\":{len}}}",
        serde_json::Number::from_f64(time.as_secs_f64()).map_or("null".into(), |n| n.to_string()),
        text(sender),
        text(type_name)
    )
}

fn run(o: &Options) -> u8 {
    // A bare location opens the connection alone (no device of this program's own).
    let name = if o.location.contains('@') {
        o.location.clone()
    } else {
        format!("{PROGRAM}@{}", o.location)
    };
    let conn = match Connection::open(&name) {
        Ok(c) => c,
        Err(e) => {
            errln!("{PROGRAM}: {e}");
            return 2;
        }
    };
    let names = Rc::new(RefCell::new(NameCache::default()));
    let json = o.json;
    conn.register_any_type_handler(SenderFilter::Any, move |m| {
        if !m.from_peer() {
            return; // the connection's own events, not messages
        }
        let c = m.connection();
        let mut cache = names.borrow_mut();
        let sender = NameCache::get(
            &mut cache.senders,
            m.sender.0,
            || c.sender_name(m.sender),
            "UNKNOWN_SENDER",
        );
        let type_name = NameCache::get(
            &mut cache.types,
            m.type_id.0,
            || c.type_name(m.type_id),
            "UNKNOWN_TYPE",
        );
        if json {
            outln!(
                "{}",
                json_line(m.sender_time, &sender, &type_name, m.payload.len())
            );
        } else {
            outln!(
                "Time: {}:{}, Sender: {sender}, Type {type_name}, Length {}",
                m.sender_time.sec,
                m.sender_time.usec,
                m.payload.len()
            );
        }
    });
    let start = Instant::now();
    while !signals::stop_requested() && !output::closed() {
        if o.seconds
            .is_some_and(|s| start.elapsed().as_secs_f64() >= s)
        {
            break;
        }
        if let Err(e) = conn.mainloop() {
            errln!("{PROGRAM}: {e}");
            return 1;
        }
        if conn.replay().is_some_and(|r| r.eof()) {
            break;
        }
        let _ = conn.wait(Duration::from_millis(10));
    }
    0
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
        Ok(Command::Print(o)) => {
            signals::install();
            run(&o)
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
