//! vrpn_log: inspects VRPN log files (`.vrpn`, as written by `vrpn_server -li/-lo` and
//! `vrpn_log_devices`): a summary, a decoded dump (text or JSON lines), and CSV export of one
//! device's reports, and plots of one device (`plot`, in `log/plot.rs`). The reading is done by
//! `vrpn::log::tools`.

#[path = "common/cli.rs"]
mod cli;
#[path = "common/output.rs"]
mod output;
#[path = "log/plot.rs"]
mod plot;

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::process::ExitCode;

use vrpn::log::tools::{self, CsvKind, Summary, Walk};
use vrpn::log::{LogError, LogReader};

use output::{errln, outln};

const PROGRAM: &str = "vrpn_log";

const USAGE: &str = "usage: vrpn_log summary FILE
       vrpn_log dump FILE [--json] [--device NAME] [--type NAME]
       vrpn_log csv FILE DEVICE [--kind KIND] [-o OUT]
       vrpn_log plot FILE DEVICE [-o OUT.png|OUT.svg]
       vrpn_log --help | --version

  summary   cookie version, duration (highest - lowest user timestamp), first and last user
            message times, per device and message type the count and average rate, and the
            system messages; a damaged tail is reported after the whole entries
  dump      one line per entry: offset, time (sec.usec), sender, type, decoded payload
            (raw hex for types it does not know)
    --json        one JSON object per line (offset, time, sec, usec, sender, sender_id, type,
                  type_id, kind, and the decoded fields)
    --device NAME only user messages from this sender
    --type NAME   only entries of this type (e.g. \"vrpn_Tracker Pos_Quat\", DISCONNECT)
  csv       one device's reports as CSV with a header row, floats in full precision
    --kind KIND   pose (default), velocity, acceleration, button, analog or dial
    -o, --output OUT
                  write to OUT instead of standard output
  plot      one device's reports as a picture: x, y, z against time and a top view per
            sensor, analog channels, button timelines, dial turns, and the intervals
            between reports with their histogram
    -o, --output OUT
                  OUT.png or OUT.svg (default DEVICE.png)
  -h, --help      print this help
  --version       print the version

Names are resolved through the descriptions inside the log; a DISCONNECT entry clears them.
Exit status: 0 on success, 1 when the file cannot be read or is damaged (the whole entries
before the damage are still processed) or the device is not in the log, 2 on a usage error.";

/// A failure to report: message for stderr, and the exit status.
struct Fail(String, u8);

/// The first three lines of [`USAGE`].
fn synopsis() -> String {
    USAGE.lines().take(3).collect::<Vec<_>>().join("\n")
}

fn usage_error(msg: impl std::fmt::Display) -> Fail {
    Fail(
        cli::usage_error(PROGRAM, &msg.to_string()),
        cli::USAGE_STATUS,
    )
}

fn log_error(e: &LogError) -> Fail {
    Fail(format!("{PROGRAM}: {e}"), 1)
}

fn io_fail(what: &str, e: io::Error) -> Fail {
    Fail(format!("{PROGRAM}: {what}: {e}"), 1)
}

/// Writes to stdout; a closed pipe (e.g. `| head`) ends the program quietly.
fn out_error(e: io::Error) -> Fail {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Fail(String::new(), 0)
    } else {
        io_fail("writing output", e)
    }
}

/// What the command line asks for.
enum Command {
    Run(Args),
    Help,
    Version,
}

/// A command with its arguments and options.
#[derive(Default)]
struct Args {
    command: String,
    /// Arguments after the command.
    positional: Vec<String>,
    /// The options given, by their long spelling, in order (to refuse the ones the command
    /// does not take).
    given: Vec<&'static str>,
    json: bool,
    device: Option<String>,
    type_name: Option<String>,
    kind: Option<String>,
    output: Option<String>,
}

fn parse_args() -> Result<Command, Fail> {
    parse_options().map_err(|e| usage_error(cli::describe(&e)))
}

fn parse_options() -> Result<Command, lexopt::Error> {
    use lexopt::prelude::*;
    let mut parser = lexopt::Parser::from_env();
    let mut a = Args::default();
    let mut command = None;
    while let Some(arg) = parser.next()? {
        let option = match arg {
            Short('h') | Long("help") => return Ok(Command::Help),
            Long("version") => return Ok(Command::Version),
            Long("json") => {
                a.json = true;
                "--json"
            }
            Long("device") => {
                a.device = Some(parser.value()?.string()?);
                "--device"
            }
            Long("type") => {
                a.type_name = Some(parser.value()?.string()?);
                "--type"
            }
            Long("kind") => {
                a.kind = Some(parser.value()?.string()?);
                "--kind"
            }
            Short('o') | Long("output") => {
                a.output = Some(parser.value()?.string()?);
                "--output"
            }
            Value(v) => {
                let v = v.string()?;
                if command.is_none() {
                    command = Some(v);
                } else {
                    a.positional.push(v);
                }
                continue;
            }
            _ => return Err(arg.unexpected()),
        };
        a.given.push(option);
    }
    match command {
        Some(c) if c == "help" => Ok(Command::Help),
        Some(c) => {
            a.command = c;
            Ok(Command::Run(a))
        }
        None => Err("no command".into()),
    }
}

impl Args {
    /// Refuses options the command does not take.
    fn only(&self, allowed: &[&str]) -> Result<(), Fail> {
        match self.given.iter().find(|o| !allowed.contains(o)) {
            Some(o) => Err(usage_error(format!("{} takes no {o} option", self.command))),
            None => Ok(()),
        }
    }

    fn file(&self, extra: usize) -> Result<&str, Fail> {
        if self.positional.len() != 1 + extra {
            return Err(usage_error(format!(
                "expected {} argument{}, got {}",
                1 + extra,
                if extra > 0 { "s" } else { "" },
                self.positional.len()
            )));
        }
        Ok(&self.positional[0])
    }
}

fn open(path: &str) -> Result<LogReader, Fail> {
    LogReader::open(path).map_err(|e| log_error(&e))
}

fn summary(args: Args) -> Result<(), Fail> {
    args.only(&[])?;
    let reader = open(args.file(0)?)?;
    let s = Summary::compute(&reader);
    let mut out = io::stdout().lock();
    write!(out, "{s}")
        .and_then(|_| out.flush())
        .map_err(out_error)?;
    match &s.damage {
        Some(e) => Err(log_error(e)),
        None => Ok(()),
    }
}

fn dump(args: Args) -> Result<(), Fail> {
    args.only(&["--json", "--device", "--type"])?;
    let reader = open(args.file(0)?)?;
    let json = args.json;
    let device = args.device.as_deref();
    let type_name = args.type_name.as_deref();
    let mut out = BufWriter::new(io::stdout().lock());
    let mut line = String::with_capacity(256);
    let (mut device_seen, mut type_seen) = (false, false);
    let mut devices: Vec<String> = Vec::new();
    let mut types: Vec<String> = Vec::new();
    let mut damage = None;
    let mut walk = Walk::new(&reader);
    while let Some(rec) = walk.next_record() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                damage = Some(e);
                break;
            }
        };
        if let Some(d) = device {
            let from = rec.is_from(d);
            device_seen |= from;
            if !from {
                if !device_seen && !rec.entry.is_system() {
                    let l = rec.sender_label();
                    if !devices.contains(&l) {
                        devices.push(l);
                    }
                }
                continue;
            }
        }
        if let Some(t) = type_name {
            let label = rec.type_label();
            if label != t {
                if !type_seen && !types.contains(&label) {
                    types.push(label);
                }
                continue;
            }
            type_seen = true;
        }
        if json {
            serde_json::to_writer(&mut out, &rec)
                .map_err(io::Error::from)
                .map_err(out_error)?;
        } else {
            line.clear();
            tools::format_text(&mut line, &rec);
            out.write_all(line.as_bytes()).map_err(out_error)?;
        }
        out.write_all(b"\n").map_err(out_error)?;
    }
    out.flush().map_err(out_error)?;
    if let Some(e) = damage {
        return Err(log_error(&e));
    }
    if let (Some(d), false) = (device, device_seen) {
        return Err(Fail(
            format!(
                "vrpn_log: no device {d:?} in {}; devices: {}",
                reader.path().display(),
                list(&devices)
            ),
            1,
        ));
    }
    if let (Some(t), false) = (type_name, type_seen) {
        let scope = device.map_or(String::new(), |d| format!(" from {d}"));
        return Err(Fail(
            format!(
                "vrpn_log: no {t:?} entries{scope} in {}; types: {}",
                reader.path().display(),
                list(&types)
            ),
            1,
        ));
    }
    Ok(())
}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "(none)".to_owned()
    } else {
        names.join(", ")
    }
}

fn csv(args: Args) -> Result<(), Fail> {
    args.only(&["--kind", "--output"])?;
    let path = args.file(1)?;
    let device = args.positional[1].as_str();
    let kind = match args.kind.as_deref() {
        None => CsvKind::Pose,
        Some(k) => CsvKind::parse(k).ok_or_else(|| {
            usage_error(format!(
                "unknown kind {k:?} (pose, velocity, acceleration, button, analog, dial)"
            ))
        })?,
    };
    let reader = open(path)?;
    let plan = tools::plan_csv(&reader, device, kind)
        .map_err(|e| Fail(format!("vrpn_log: {}: {e}", reader.path().display()), 1))?;
    let result = match args.output.as_deref() {
        Some(out_path) if out_path != "-" => {
            let file = File::create(out_path)
                .map_err(|e| io_fail(&format!("cannot create output file {out_path}"), e))?;
            let mut w = BufWriter::new(file);
            let r = tools::write_csv(&reader, &plan, &mut w).and_then(|r| w.flush().map(|_| r));
            r.map_err(|e| io_fail(&format!("writing output file {out_path}"), e))?
        }
        _ => {
            let mut w = BufWriter::new(io::stdout().lock());
            let r = tools::write_csv(&reader, &plan, &mut w).and_then(|r| w.flush().map(|_| r));
            r.map_err(out_error)?
        }
    };
    match result.1 {
        Some(e) => Err(log_error(&e)),
        None => Ok(()),
    }
}

fn plot_command(args: Args) -> Result<(), Fail> {
    args.only(&["--output"])?;
    let path = args.file(1)?;
    let device = args.positional[1].as_str();
    let default_out = format!("{}.png", device.replace(['/', ' '], "_"));
    let out = args.output.as_deref().unwrap_or(&default_out);
    let format = plot::Format::of(out).ok_or_else(|| {
        usage_error(format!(
            "cannot tell the format of {out:?}: name it .png or .svg"
        ))
    })?;
    let reader = open(path)?;
    let r = plot::read(&reader, device);
    if !r.found {
        let e = format!(
            "vrpn_log: no device {device:?} in {}; devices: {}",
            reader.path().display(),
            list(&r.devices)
        );
        return Err(Fail(e, 1));
    }
    if r.data.is_empty() {
        let e = format!(
            "vrpn_log: {device} sent no tracker, analog, button or dial reports in {}",
            reader.path().display()
        );
        return Err(Fail(e, 1));
    }
    plot::render(&r.data, out, format).map_err(|e| Fail(format!("vrpn_log: {out}: {e}"), 1))?;
    match r.damage {
        Some(e) => Err(log_error(&e)),
        None => Ok(()),
    }
}

fn run() -> Result<(), Fail> {
    if std::env::args_os().len() < 2 {
        return Err(Fail(synopsis(), cli::USAGE_STATUS));
    }
    let args = match parse_args()? {
        Command::Help => {
            outln!("{USAGE}");
            return Ok(());
        }
        Command::Version => {
            outln!("{}", cli::version(PROGRAM));
            return Ok(());
        }
        Command::Run(args) => args,
    };
    match args.command.as_str() {
        "summary" => summary(args),
        "dump" => dump(args),
        "csv" => csv(args),
        "plot" => plot_command(args),
        other => Err(usage_error(format!("unknown command {other:?}"))),
    }
}

fn main() -> ExitCode {
    let status = match run() {
        Ok(()) => 0,
        Err(Fail(msg, code)) => {
            if !msg.is_empty() {
                errln!("{msg}");
            }
            code
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
