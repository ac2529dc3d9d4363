//! vrpn_device_sim: one of this crate's device simulators on a pseudo-terminal, so that a
//! `vrpn.cfg` line can be tried without the hardware (by our server or any other).

#[allow(dead_code)]
#[path = "common/cli.rs"]
mod cli;
#[allow(dead_code)]
#[path = "common/output.rs"]
mod output;
#[path = "common/signals.rs"]
mod signals;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use nix::poll::{poll, PollFd, PollFlags};
use vrpn::drivers::SIMULATORS;
use vrpn::sim::{PtyDevice, Simulator};
use vrpn::Now;

use output::{errln, outln};

const PROGRAM: &str = "vrpn_device_sim";

const USAGE: &str = "usage: vrpn_device_sim KIND PATH [-b BAUD] [-s SECONDS]
       vrpn_device_sim --list | --help | --version
  Runs the simulated device KIND on a pseudo-terminal reachable at PATH (a symbolic link
  this program creates and removes), until Ctrl-C or SECONDS, and prints the vrpn.cfg line
  that serves it. The device answers its driver's reset and streams known values.
  -b, --baud BAUD     the line's speed (default: the one vrpn.cfg.sample uses for KIND)
  -s, --seconds N     stop after N seconds
  -l, --list          list the simulators, their default speeds and vrpn.cfg lines
  -h, --help          print this help
  --version           print the version";

/// What the command line asks for.
enum Command {
    Run {
        sim: &'static Simulator,
        path: PathBuf,
        baud: Option<u32>,
        seconds: Option<f64>,
    },
    List,
    Help,
    Version,
}

fn find(kind: &str) -> Result<&'static Simulator, lexopt::Error> {
    SIMULATORS
        .iter()
        .copied()
        .find(|s| s.name == kind)
        .ok_or_else(|| {
            let names: Vec<&str> = SIMULATORS.iter().map(|s| s.name).collect();
            format!("no simulator {kind:?} (there are: {})", names.join(", ")).into()
        })
}

fn parse_args() -> Result<Command, lexopt::Error> {
    use lexopt::prelude::*;
    let mut parser = lexopt::Parser::from_env();
    let (mut kind, mut path, mut baud, mut seconds) = (None, None, None, None);
    while let Some(arg) = parser.next()? {
        match arg {
            Short('b') | Long("baud") => baud = Some(cli::value(&mut parser, "-b", "a baud rate")?),
            Short('s') | Long("seconds") => {
                let s: f64 = cli::value(&mut parser, "-s", "a number of seconds")?;
                if !(s.is_finite() && s > 0.0) {
                    return Err(format!("-s needs a positive number of seconds, got {s}").into());
                }
                seconds = Some(s);
            }
            Short('l') | Long("list") => return Ok(Command::List),
            Short('h') | Long("help") => return Ok(Command::Help),
            Long("version") => return Ok(Command::Version),
            Value(v) if kind.is_none() => kind = Some(v.string()?),
            Value(v) if path.is_none() => path = Some(PathBuf::from(v)),
            _ => return Err(arg.unexpected()),
        }
    }
    match (kind, path) {
        (Some(kind), Some(path)) => Ok(Command::Run {
            sim: find(&kind)?,
            path,
            baud,
            seconds,
        }),
        _ => Err("a simulator KIND and a PATH are needed (see --help)".into()),
    }
}

fn main() -> ExitCode {
    let (sim, path, baud, seconds) = match parse_args() {
        Ok(Command::Run {
            sim,
            path,
            baud,
            seconds,
        }) => (sim, path, baud, seconds),
        Ok(Command::List) => {
            for s in SIMULATORS {
                outln!("{:<10} {}", s.name, s.about);
                let baud = if s.baud == 0 {
                    "not a serial line".to_owned()
                } else {
                    format!("{} baud", s.baud)
                };
                outln!("{:<10} {baud}: {}", "", s.config_line("PATH", s.baud));
            }
            return ExitCode::SUCCESS;
        }
        Ok(Command::Help) => {
            outln!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Ok(Command::Version) => {
            outln!("{PROGRAM} {}", env!("CARGO_PKG_VERSION"));
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            errln!("{PROGRAM}: {e}");
            return ExitCode::from(2);
        }
    };
    signals::install();
    let baud = baud.unwrap_or(sim.baud);
    let mut device = match PtyDevice::open((sim.make)(baud), &path) {
        Ok(d) => d,
        Err(e) => {
            errln!("{PROGRAM}: {}: {e}", path.display());
            return ExitCode::from(1);
        }
    };
    outln!(
        "{PROGRAM}: {} on {} ({}); serve it with:\n{}",
        sim.name,
        path.display(),
        if baud == 0 {
            "not a serial line".to_owned()
        } else {
            format!("{baud} baud")
        },
        sim.config_line(&path.display().to_string(), baud)
    );
    let end = seconds.map(|s| Instant::now() + Duration::from_secs_f64(s));
    while !signals::stop_requested() && !output::closed() {
        let now = Now::read();
        if end.is_some_and(|e| now.mono >= e) {
            break;
        }
        if let Err(e) = device.step(now) {
            errln!("{PROGRAM}: {}: {e}", path.display());
            return ExitCode::from(1);
        }
        // Wait for the driver's bytes or the device's next output, whichever comes first
        // (at most 1 ms: the simulated line paces its bytes at the baud rate).
        let wait = device
            .next_deadline()
            .map_or(Duration::from_millis(1), |d| {
                d.saturating_duration_since(Instant::now())
            })
            .min(Duration::from_millis(1));
        if let Some(fd) = device.master_fd() {
            let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
            let _ = poll(&mut fds, wait.as_millis().max(1) as i32);
        } else {
            std::thread::sleep(wait);
        }
    }
    ExitCode::SUCCESS
}
