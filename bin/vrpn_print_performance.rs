//! vrpn_print_performance: opens each named device and prints, once per report interval, the
//! rate of its tracker reports (per sensor and kind) and analog reports, and each button
//! change, in C++'s line formats.

#[path = "common/cli.rs"]
mod cli;
#[path = "common/output.rs"]
mod output;
#[path = "common/signals.rs"]
mod signals;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use vrpn::{AnalogRemote, ButtonRemote, TrackerRemote};

use output::{errln, outln};

const PROGRAM: &str = "vrpn_print_performance";

const USAGE: &str = "usage: vrpn_print_performance [--notracker] [--nobutton] [--noanalog]
                              [--reportinterval N] [--seconds S] DEVICE@HOST[:PORT]...
       vrpn_print_performance --help | --version
  --notracker         do not report tracker rates of the devices that follow
  --nobutton          do not print button changes of the devices that follow
  --noanalog          do not report analog rates of the devices that follow
  --reportinterval N  print the rates every N seconds (N >= 1, default 1)
  --seconds S         exit after S seconds (default: run until interrupted)
  -h, --help          print this help
  --version           print the version
  (the C++ spellings with one dash, -notracker and the others, are accepted too)";

const CPP_OPTIONS: &[&str] = &["notracker", "nobutton", "noanalog", "reportinterval"];

#[derive(Clone, Copy)]
struct Shown {
    tracker: bool,
    button: bool,
    analog: bool,
}

struct Options {
    interval: f64,
    seconds: Option<f64>,
    devices: Vec<(String, Shown)>,
}

enum Command {
    Run(Options),
    Help,
    Version,
}

fn parse_args() -> Result<Command, lexopt::Error> {
    use lexopt::prelude::*;
    let mut parser = lexopt::Parser::from_args(cli::with_cpp_spellings(CPP_OPTIONS));
    let mut shown = Shown {
        tracker: true,
        button: true,
        analog: true,
    };
    let mut o = Options {
        interval: 1.0,
        seconds: None,
        devices: Vec::new(),
    };
    while let Some(arg) = parser.next()? {
        match arg {
            Long("notracker") => shown.tracker = false,
            Long("nobutton") => shown.button = false,
            Long("noanalog") => shown.analog = false,
            Long("reportinterval") => {
                let n: u32 = cli::value(&mut parser, "--reportinterval", "a whole number")?;
                if n == 0 {
                    return Err("--reportinterval argument must be 1 or greater".into());
                }
                o.interval = f64::from(n);
            }
            Long("seconds") => {
                let s: f64 = cli::value(&mut parser, "--seconds", "a number of seconds")?;
                if !(s.is_finite() && s >= 0.0) {
                    return Err(format!("--seconds needs a number of seconds, got {s}").into());
                }
                o.seconds = Some(s);
            }
            Short('h') | Long("help") => return Ok(Command::Help),
            Long("version") => return Ok(Command::Version),
            Value(name) => o.devices.push((name.string()?, shown)),
            _ => return Err(arg.unexpected()),
        }
    }
    if o.devices.is_empty() {
        return Err("name at least one DEVICE@HOST".into());
    }
    Ok(Command::Run(o))
}

/// Counts reports of one kind, per sensor, and says when an interval is over.
struct Rate {
    interval: f64,
    counts: Vec<(u64, Instant)>,
}

impl Rate {
    fn new(interval: f64) -> Rate {
        Rate {
            interval,
            counts: Vec::new(),
        }
    }

    /// Counts a report of `sensor` at `now`; at the end of an interval returns the rate and
    /// the interval's length, and starts the next.
    fn count(&mut self, sensor: usize, now: Instant) -> Option<(f64, f64)> {
        if self.counts.len() <= sensor {
            self.counts.resize(sensor + 1, (0, now));
        }
        let (n, since) = &mut self.counts[sensor];
        *n += 1;
        let elapsed = now.duration_since(*since).as_secs_f64();
        if elapsed < self.interval {
            return None;
        }
        let rate = *n as f64 / elapsed;
        *n = 0;
        *since = now;
        Some((rate, elapsed))
    }
}

struct Device {
    tracker: TrackerRemote,
    button: ButtonRemote,
    analog: AnalogRemote,
}

fn open(name: &str, shown: Shown, interval: f64) -> Result<Device, vrpn::Error> {
    let tracker = TrackerRemote::new(name)?;
    let button = ButtonRemote::new(name)?;
    let analog = AnalogRemote::new(name)?;
    let mut line = format!("Opened {name} as:");
    if shown.tracker {
        line.push_str(" Tracker");
        let (n, mut rate) = (name.to_string(), Rate::new(interval));
        tracker.on_pose(move |p| {
            if let Some((hz, secs)) = rate.count(p.sensor, Instant::now()) {
                outln!(
                    "Tracker {n}, sensor {}:\t{hz:5.2} Hz ({secs:5.2} sec)",
                    p.sensor
                );
            }
        });
        for kind in 0..2 {
            let (n, mut rate) = (name.to_string(), Rate::new(interval));
            let mut print = move |sensor: usize| {
                if let Some((hz, secs)) = rate.count(sensor, Instant::now()) {
                    outln!(
                        "Tracker {n}, sensor {sensor}:\t\t{hz:5.2} messages per second \
                         averaged over {secs:5.2} seconds"
                    );
                }
            };
            if kind == 0 {
                tracker.on_velocity(move |v| print(v.sensor));
            } else {
                tracker.on_acceleration(move |a| print(a.sensor));
            }
        }
    }
    if shown.button {
        line.push_str(" Button");
        let n = name.to_string();
        button.on_change(move |c| {
            let what = if c.state.is_pressed() {
                "pressed"
            } else {
                "released"
            };
            outln!("Button {n}, number {} was just {what}", c.button);
        });
    }
    if shown.analog {
        line.push_str(" Analog");
        let (n, mut rate) = (name.to_string(), Rate::new(interval));
        analog.on_report(move |_| {
            if let Some((hz, secs)) = rate.count(0, Instant::now()) {
                outln!(
                    "Analog {n}:\t\t{hz:5.2} messages per second averaged over {secs:5.2} seconds"
                );
            }
        });
    }
    outln!("{line}.");
    Ok(Device {
        tracker,
        button,
        analog,
    })
}

fn run(o: &Options) -> u8 {
    let mut devices = Vec::new();
    for (name, shown) in &o.devices {
        match open(name, *shown, o.interval) {
            Ok(d) => devices.push(d),
            Err(e) => {
                errln!("{PROGRAM}: {name}: {e}");
                return 2;
            }
        }
    }
    outln!("Press ^C to exit.");
    let start = Instant::now();
    while !signals::stop_requested() && !output::closed() {
        if o.seconds
            .is_some_and(|s| start.elapsed().as_secs_f64() >= s)
        {
            break;
        }
        for d in &devices {
            let r = d
                .tracker
                .mainloop()
                .and_then(|()| d.button.mainloop())
                .and_then(|()| d.analog.mainloop());
            if let Err(e) = r {
                errln!("{PROGRAM}: {e}");
                return 1;
            }
        }
        if let Some(d) = devices.first() {
            let _ = d.tracker.connection().wait(Duration::from_millis(10));
        }
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
        Ok(Command::Run(o)) => {
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
