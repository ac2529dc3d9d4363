//! vrpn_log: inspects VRPN log files (`.vrpn`, as written by `vrpn_server -li/-lo` and
//! `vrpn_log_devices`): a summary, a decoded dump (text or JSON lines), and CSV export of one
//! device's reports. The work is done by `vrpn::log::tools`.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::process::ExitCode;

use vrpn::log::tools::{self, CsvKind, Summary, Walk};
use vrpn::log::{LogError, LogReader};

const USAGE: &str = "usage: vrpn_log summary FILE
       vrpn_log dump FILE [--json] [--device NAME] [--type NAME]
       vrpn_log csv FILE DEVICE [--kind KIND] [-o OUT]

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
    -o OUT        write to OUT instead of standard output

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
        format!("vrpn_log: {msg}\n{}\n(vrpn_log -h for details)", synopsis()),
        2,
    )
}

fn log_error(e: &LogError) -> Fail {
    Fail(format!("vrpn_log: {e}"), 1)
}

fn io_fail(what: &str, e: io::Error) -> Fail {
    Fail(format!("vrpn_log: {what}: {e}"), 1)
}

/// Writes to stdout; a closed pipe (e.g. `| head`) ends the program quietly.
fn out_error(e: io::Error) -> Fail {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Fail(String::new(), 0)
    } else {
        io_fail("writing output", e)
    }
}

/// Splits arguments into positionals and `--option VALUE` / flag pairs.
struct Args {
    positional: Vec<String>,
    options: Vec<(String, Option<String>)>,
}

fn parse_args(
    args: impl Iterator<Item = String>,
    flags: &[&str],
    valued: &[&str],
) -> Result<Args, Fail> {
    let mut a = Args {
        positional: Vec::new(),
        options: Vec::new(),
    };
    let mut args = args.peekable();
    while let Some(s) = args.next() {
        if s == "--" {
            a.positional.extend(args.by_ref());
            break;
        }
        if flags.contains(&s.as_str()) {
            a.options.push((s, None));
        } else if valued.contains(&s.as_str()) {
            match args.next() {
                Some(v) => a.options.push((s, Some(v))),
                None => return Err(usage_error(format!("{s} needs a value"))),
            }
        } else if s.starts_with('-') && s.len() > 1 {
            return Err(usage_error(format!("unknown option {s}")));
        } else {
            a.positional.push(s);
        }
    }
    Ok(a)
}

impl Args {
    fn flag(&self, name: &str) -> bool {
        self.options.iter().any(|(k, _)| k == name)
    }

    fn value(&self, names: &[&str]) -> Option<&str> {
        self.options
            .iter()
            .rev()
            .find(|(k, _)| names.contains(&k.as_str()))
            .and_then(|(_, v)| v.as_deref())
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
    let reader = open(args.file(0)?)?;
    let json = args.flag("--json");
    let device = args.value(&["--device"]);
    let type_name = args.value(&["--type"]);
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
        line.clear();
        if json {
            tools::format_json(&mut line, &rec);
        } else {
            tools::format_text(&mut line, &rec);
        }
        line.push('\n');
        out.write_all(line.as_bytes()).map_err(out_error)?;
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
    let path = args.file(1)?;
    let device = args.positional[1].as_str();
    let kind = match args.value(&["--kind"]) {
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
    let result = match args.value(&["-o", "--output"]) {
        Some(out_path) if out_path != "-" => {
            let file = File::create(out_path).map_err(|e| io_fail(out_path, e))?;
            let mut w = BufWriter::new(file);
            let r = tools::write_csv(&reader, &plan, &mut w).and_then(|r| w.flush().map(|_| r));
            r.map_err(|e| io_fail(out_path, e))?
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

fn run() -> Result<(), Fail> {
    let mut args = std::env::args().skip(1);
    let Some(cmd) = args.next() else {
        return Err(Fail(synopsis(), 2));
    };
    let rest: Vec<String> = args.collect();
    if matches!(cmd.as_str(), "-h" | "--help" | "help")
        || rest.iter().any(|a| a == "-h" || a == "--help")
    {
        println!("{USAGE}");
        return Ok(());
    }
    let rest = rest.into_iter();
    match cmd.as_str() {
        "summary" => summary(parse_args(rest, &[], &[])?),
        "dump" => dump(parse_args(rest, &["--json"], &["--device", "--type"])?),
        "csv" => csv(parse_args(rest, &[], &["--kind", "-o", "--output"])?),
        other => Err(usage_error(format!("unknown command {other:?}"))),
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(Fail(msg, code)) => {
            if !msg.is_empty() {
                eprintln!("{msg}");
            }
            ExitCode::from(code)
        }
    }
}
