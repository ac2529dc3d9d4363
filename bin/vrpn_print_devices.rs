//! vrpn_print_devices: opens each named device and prints every report, like the C++ tool;
//! `--json` prints one JSON object per line; `--list HOST[:PORT]` prints the device names a
//! server announces.

#[path = "common/cli.rs"]
mod cli;
#[path = "common/output.rs"]
mod output;
#[path = "common/signals.rs"]
mod signals;

use std::cell::Cell;
use std::fmt::Write as _;
use std::process::ExitCode;
use std::rc::Rc;
use std::time::{Duration, Instant};

use serde::ser::{SerializeMap, Serializer as _};
use serde_json::ser::{CompactFormatter, Compound};
use vrpn::connection::{set_text_printer, TextPrinter};
use vrpn::{
    AnalogRemote, ButtonRemote, Connection, ConnectionState, DeviceName, DialRemote, NoticeKind,
    TextReceiver, TextSeverity, TimeVal, TrackerRemote,
};

use output::{errln, outln};

const PROGRAM: &str = "vrpn_print_devices";

const USAGE: &str =
    "usage: vrpn_print_devices [--json] [--seconds S] [--log FILE] [-rli FILE] [-rlo FILE]
                          [-notracker] [-nobutton]
                          [-noanalog] [-nodial] [-notext] [-trackerstride N]
                          DEVICE@HOST[:PORT]...
       vrpn_print_devices --list HOST[:PORT]
       vrpn_print_devices --help | --version
  DEVICE@HOST        e.g. Tracker0@localhost, Tracker0@tcp://host:3883, Tracker0@host:3884
  --json             one JSON object per report: device, kind, time (local clock),
                     server_time (as stamped by the server), clock_offset and
                     clock_uncertainty once the clocks are synchronised, and the values
  --seconds S        exit after S seconds (default: run until interrupted)
  --log FILE         log every message received to FILE (C++ .vrpn format; one file per
                     server: FILE-2.vrpn, … for the second and later); replay it with
                     DEVICE@file:FILE
  --until-eof        with DEVICE@file:FILE names only: exit once every file has been
                     replayed to its end
  -rli FILE          ask each server to log what it receives from us to FILE, on its
                     machine (C++ remote logging; a server of this crate writes it inside
                     its -logdir folder, and only under a plain file name)
  -rlo FILE          ask each server to log what it sends us to FILE, on its machine
  -notracker         do not print tracker reports of the devices that follow
  -nobutton          do not print button reports of the devices that follow
  -noanalog          do not print analog reports of the devices that follow
  -nodial            do not print dial reports of the devices that follow
  -notext            do not print text messages (warnings and errors included) of the
                     devices that follow
  -trackerstride N   print every Nth report of each tracker sensor of the devices that
                     follow (N >= 1)
                     (each of these also takes two dashes: --notracker, --trackerstride N)
  --list HOST[:PORT] print the device names the server announces, then exit
  -h, --help         print this help
  --version          print the version
Reports (and the devices' text messages) go to stdout; notices, warnings and errors go to
stderr, one line each, prefixed with the program name.
Exit status: 0 when stopped (^C, --seconds, closed output, --until-eof), 1 when a server
offers no device of a name given, 2 for a bad name or option.";

/// The C++ options spelt with one dash.
const CPP_OPTIONS: &[&str] = &[
    "rli",
    "rlo",
    "notracker",
    "nobutton",
    "noanalog",
    "nodial",
    "notext",
    "trackerstride",
];

/// What the command line asks for.
enum Command {
    Print(PrintOptions),
    List(String),
    Help,
    Version,
}

/// Which reports of a device are printed (the options before its name, as in C++).
#[derive(Clone, Copy)]
struct Shown {
    tracker: bool,
    button: bool,
    analog: bool,
    dial: bool,
    text: bool,
    /// Every Nth report of each tracker sensor.
    tracker_stride: u32,
}

impl Default for Shown {
    fn default() -> Self {
        Shown {
            tracker: true,
            button: true,
            analog: true,
            dial: true,
            text: true,
            tracker_stride: 1,
        }
    }
}

/// Options of the report printer.
#[derive(Default)]
struct PrintOptions {
    json: bool,
    seconds: Option<f64>,
    log: Option<String>,
    until_eof: bool,
    remote_in: Option<String>,
    remote_out: Option<String>,
    names: Vec<(String, Shown)>,
}

fn parse_args() -> Result<Command, lexopt::Error> {
    use lexopt::prelude::*;
    let mut parser = lexopt::Parser::from_args(cli::with_cpp_spellings(CPP_OPTIONS));
    let mut o = PrintOptions::default();
    let mut list = None;
    let mut shown = Shown::default();
    while let Some(arg) = parser.next()? {
        match arg {
            Long("json") => o.json = true,
            Long("seconds") => {
                let s: f64 = cli::value(&mut parser, "--seconds", "a number of seconds")?;
                if !(s.is_finite() && s >= 0.0) {
                    return Err(format!("--seconds needs a number of seconds, got {s}").into());
                }
                o.seconds = Some(s);
            }
            Long("log") => o.log = Some(parser.value()?.string()?),
            Long("until-eof") => o.until_eof = true,
            Long("rli") => o.remote_in = Some(parser.value()?.string()?),
            Long("rlo") => o.remote_out = Some(parser.value()?.string()?),
            Long("list") => list = Some(parser.value()?.string()?),
            Long("notracker") => shown.tracker = false,
            Long("nobutton") => shown.button = false,
            Long("noanalog") => shown.analog = false,
            Long("nodial") => shown.dial = false,
            Long("notext") => shown.text = false,
            Long("trackerstride") => {
                let n: u32 = cli::value(&mut parser, "-trackerstride", "a whole number")?;
                if n == 0 {
                    return Err("-trackerstride argument must be 1 or greater".into());
                }
                shown.tracker_stride = n;
            }
            Short('h') | Long("help") => return Ok(Command::Help),
            Long("version") => return Ok(Command::Version),
            Value(name) => o.names.push((name.string()?, shown)),
            _ => return Err(arg.unexpected()),
        }
    }
    match list {
        Some(location) if o.names.is_empty() => Ok(Command::List(location)),
        Some(_) => Err("--list takes no device names".into()),
        None if o.names.is_empty() => Err("name at least one DEVICE@HOST".into()),
        None if o.until_eof && !o.names.iter().all(|(n, _)| is_replay(n)) => {
            Err("--until-eof needs DEVICE@file:FILE names (a live device has no end)".into())
        }
        None => Ok(Command::Print(o)),
    }
}

/// True for a `DEVICE@file:PATH` name (a replay, which has an end).
fn is_replay(name: &str) -> bool {
    matches!(
        DeviceName::parse(name).map(|n| n.location),
        Ok(vrpn::Location::File { .. })
    )
}

/// Output streams: data (reports, device texts) on stdout, diagnostics on stderr, once. The
/// library's default printer would write device warnings to stderr beside the report line
/// and notices in its own format; it is turned off and each connection's notices come here.
fn report_notices(conn: &Connection, missing: Option<&Missing>) {
    let missing = missing.cloned();
    conn.on_notice(move |n| {
        errln!("{PROGRAM}: {}", n.text);
        // The server offers no device of a name given: nothing will ever come of it.
        if let (NoticeKind::NoSuchDevice { device, .. }, Some(m)) = (&n.kind, &missing) {
            let mut m = m.borrow_mut();
            if !m.contains(device) {
                m.push(device.clone());
            }
        }
    });
}

/// The device names servers said they do not offer.
type Missing = Rc<std::cell::RefCell<Vec<String>>>;

/// The clock-synchronisation estimate of a device's connection as of the last loop pass:
/// offset (server clock minus ours) and its uncertainty, in seconds; `None` while no sync is in
/// effect (a C++ server never answers the exchange).
type ClockView = Rc<Cell<Option<(f64, f64)>>>;

/// A report's two timestamps: `time` in local time when sync is in effect (else as stamped),
/// `sender_time` as the server stamped it.
#[derive(Clone, Copy)]
struct Stamp {
    time: TimeVal,
    sender_time: TimeVal,
}

/// Formats one JSON report line: `device`, `kind`, `time` (local-clock seconds since the epoch,
/// translated when clock sync is in effect), `server_time` (as the server stamped it) and, once
/// known, `clock_offset` and `clock_uncertainty` (seconds); then the fields `fields` adds, in
/// that order.
fn json_report(
    device: &str,
    kind: &str,
    stamp: Stamp,
    clock: &ClockView,
    fields: impl FnOnce(&mut Compound<'_, &mut Vec<u8>, CompactFormatter>) -> serde_json::Result<()>,
) -> String {
    let mut buf = Vec::with_capacity(256);
    let mut ser = serde_json::Serializer::new(&mut buf);
    let written = ser.serialize_map(None).and_then(|mut map| {
        map.serialize_entry("device", device)?;
        map.serialize_entry("kind", kind)?;
        map.serialize_entry("time", &stamp.time.as_secs_f64())?;
        map.serialize_entry("server_time", &stamp.sender_time.as_secs_f64())?;
        if let Some((offset, uncertainty)) = clock.get() {
            map.serialize_entry("clock_offset", &offset)?;
            map.serialize_entry("clock_uncertainty", &uncertainty)?;
        }
        fields(&mut map)?;
        map.end()
    });
    // Into memory, from strings and numbers (non-finite ones become null): cannot fail.
    written.expect("JSON into memory");
    String::from_utf8(buf).expect("serde_json writes UTF-8")
}

/// Prints the device names the server at `location` announces. Returns the exit status.
fn list(location: &str) -> u8 {
    let name = format!("{PROGRAM}@{location}");
    let conn = match Connection::open(&name) {
        Ok(c) => c,
        Err(e) => {
            errln!("{PROGRAM}: {e}");
            return 2;
        }
    };
    report_notices(&conn, None);
    let start = Instant::now();
    let mut connected_at = None;
    while start.elapsed() < Duration::from_secs(10) && !signals::stop_requested() {
        let _ = conn.mainloop();
        if conn.state() == ConnectionState::Connected && connected_at.is_none() {
            connected_at = Some(Instant::now());
        }
        // Descriptions arrive right after the cookie; give late ones a moment.
        if connected_at.is_some_and(|t| t.elapsed() > Duration::from_millis(300)) {
            // Not devices: the server's services and our own name echoed back.
            for s in conn.peer_devices() {
                if s != PROGRAM {
                    outln!("{s}");
                }
            }
            return 0;
        }
        let _ = conn.wait(Duration::from_millis(10));
    }
    if signals::stop_requested() {
        return 0;
    }
    errln!("{PROGRAM}: no VRPN server answered at {location} within 10 s");
    1
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
        Ok(Command::List(location)) => {
            signals::install();
            set_text_printer(TextPrinter::Off);
            list(&location)
        }
        Ok(Command::Print(options)) => {
            signals::install();
            set_text_printer(TextPrinter::Off);
            print(&options)
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

/// The remotes of one named device.
struct Opened {
    /// The name as given.
    name: String,
    /// Its connection's clock estimate, updated every pass for the printers.
    clock: ClockView,
    /// JSON output (no clock lines).
    json: bool,
    tracker: TrackerRemote,
    button: ButtonRemote,
    analog: AnalogRemote,
    dial: DialRemote,
    text: TextReceiver,
}

impl Opened {
    fn mainloop(&self) -> Result<(), vrpn::Error> {
        self.update_clock();
        self.tracker.mainloop()?;
        self.button.mainloop()?;
        self.analog.mainloop()?;
        self.dial.mainloop()?;
        self.text.mainloop()
    }

    /// Takes the connection's clock estimate for this pass's reports, and says (in the text
    /// format) when synchronisation comes into effect or lapses.
    fn update_clock(&self) {
        let now = self
            .tracker
            .connection()
            .clock_estimate()
            .map(|e| (e.offset, e.uncertainty));
        let was = self.clock.replace(now);
        if self.json || was.is_some() == now.is_some() {
            return;
        }
        let _ = match now {
            Some((offset, uncertainty)) => outln!(
                "Clock of {}: server clock {offset:+.6} s from ours (± {uncertainty:.6} s); \
                 report times are in local time",
                self.name
            ),
            None => outln!(
                "Clock of {}: synchronisation lapsed; report times are the server's",
                self.name
            ),
        };
    }
}

/// Opens every device and prints its reports until the time is up, a signal comes or the
/// output is closed. Returns the exit status.
fn print(o: &PrintOptions) -> u8 {
    let mut devices = Vec::new();
    let mut logged: Vec<Connection> = Vec::new();
    let mut watched: Vec<Connection> = Vec::new();
    // The names a server says it does not offer: nothing will ever come of them.
    let missing: Missing = Rc::default();
    for (name, shown) in &o.names {
        let (name, shown) = (name.as_str(), *shown);
        if let Err(e) = DeviceName::parse(name) {
            errln!("{PROGRAM}: {e}");
            return 2;
        }
        let tracker = match TrackerRemote::new(name) {
            Ok(t) => t,
            Err(e) => {
                errln!("{PROGRAM}: {name}: {e}");
                return 2;
            }
        };
        if !watched.iter().any(|c| c.same_as(tracker.connection())) {
            report_notices(tracker.connection(), Some(&missing));
            watched.push(tracker.connection().clone());
        }
        if o.remote_in.is_some() || o.remote_out.is_some() {
            let conn = tracker.connection();
            let asked = conn.request_remote_logging(
                o.remote_in.as_deref().unwrap_or(""),
                o.remote_out.as_deref().unwrap_or(""),
            );
            if let Err(e) = asked {
                errln!("{PROGRAM}: {name}: -rli/-rlo: {e}");
                return 2;
            }
        }
        if let Some(path) = &o.log {
            let conn = tracker.connection();
            if !logged.iter().any(|c: &Connection| c.same_as(conn)) {
                let file = match logged.len() {
                    0 => path.clone(),
                    n => match path.rfind('.') {
                        Some(i) => format!("{}-{}{}", &path[..i], n + 1, &path[i..]),
                        None => format!("{path}-{}", n + 1),
                    },
                };
                if let Err(e) = conn.log_incoming(&file) {
                    errln!("{PROGRAM}: --log: {e}");
                    return 2;
                }
                logged.push(conn.clone());
            }
        }
        let opened = match open_others(name, tracker, o.json, shown) {
            Ok(d) => d,
            Err(e) => {
                errln!("{PROGRAM}: {name}: {e}");
                return 2;
            }
        };
        if !o.json {
            let kinds = [
                (shown.tracker, " Tracker"),
                (shown.button, " Button"),
                (shown.analog, " Analog"),
                (shown.dial, " Dial"),
                (shown.text, " Text"),
            ];
            let mut line = format!("Opened {name} as:");
            for (on, kind) in kinds {
                if on {
                    line.push_str(kind);
                }
            }
            outln!("{line}.");
        }
        devices.push(opened);
    }
    if !o.json {
        outln!("Press ^C to exit.");
    }
    let start = Instant::now();
    while !signals::stop_requested() && !output::closed() {
        if o.seconds
            .is_some_and(|s| start.elapsed().as_secs_f64() >= s)
        {
            break;
        }
        for d in &devices {
            if let Err(e) = d.mainloop() {
                errln!("{PROGRAM}: {e}");
                return 1;
            }
        }
        // Every device named is missing: nothing will ever be printed.
        if missing.borrow().len() == devices.len() {
            break;
        }
        if o.until_eof && watched.iter().all(replay_done) {
            break;
        }
        // Sleep until data arrives (or 10 ms for ping timers and reconnect attempts).
        if let Some(d) = devices.first() {
            let _ = d.tracker.connection().wait(Duration::from_millis(10));
        }
    }
    // A device a server does not offer is an error, whether or not others printed.
    let any_missing = !missing.borrow().is_empty();
    u8::from(any_missing)
}

/// True once a replay connection has played every message of its file.
fn replay_done(conn: &Connection) -> bool {
    conn.replay().is_some_and(|r| r.eof())
}

/// Every Nth report of each sensor (C++ `-trackerstride`: the Nth, 2Nth, … are printed).
struct Stride {
    every: u32,
    counts: Vec<u32>,
}

impl Stride {
    fn new(every: u32) -> Stride {
        Stride {
            every,
            counts: Vec::new(),
        }
    }

    /// Counts a report of `sensor`; true when it is one to print.
    fn take(&mut self, sensor: usize) -> bool {
        if self.every <= 1 {
            return true;
        }
        if self.counts.len() <= sensor {
            self.counts.resize(sensor + 1, 0);
        }
        self.counts[sensor] += 1;
        if self.counts[sensor] >= self.every {
            self.counts[sensor] = 0;
            true
        } else {
            false
        }
    }
}

/// Attaches the tracker printers to `tracker` (the C++ formats, or JSON objects of kind pose,
/// velocity and acceleration).
fn print_tracker(tracker: &TrackerRemote, label: &str, json: bool, clock: &ClockView, stride: u32) {
    let device = tracker.device().to_string();
    let (d, l, ck) = (device.clone(), label.to_owned(), clock.clone());
    let mut due = Stride::new(stride);
    tracker.on_pose(move |r| {
        if !due.take(r.sensor) {
            return;
        }
        if json {
            outln!(
                "{}",
                json_report(&d, "pose", Stamp { time: r.time, sender_time: r.sender_time }, &ck, |m| {
                    m.serialize_entry("sensor", &r.sensor)?;
                    m.serialize_entry("pos", &[r.pos.x, r.pos.y, r.pos.z])?;
                    m.serialize_entry("quat", &[r.quat.i, r.quat.j, r.quat.k, r.quat.w])
                })
            );
        } else {
            outln!(
                "Tracker {l}, sensor {}:\n     pos ({:5.2}, {:5.2}, {:5.2}); quat ({:5.2}, {:5.2}, {:5.2}, {:5.2})",
                r.sensor, r.pos.x, r.pos.y, r.pos.z, r.quat.i, r.quat.j, r.quat.k, r.quat.w
            );
        }
    });
    let (d, l, ck) = (device.clone(), label.to_owned(), clock.clone());
    let mut due = Stride::new(stride);
    tracker.on_velocity(move |r| {
        if !due.take(r.sensor) {
            return;
        }
        let q = &r.vel_quat;
        if json {
            let w = r.angular_velocity();
            outln!(
                "{}",
                json_report(&d, "velocity", Stamp { time: r.time, sender_time: r.sender_time }, &ck, |m| {
                    m.serialize_entry("sensor", &r.sensor)?;
                    m.serialize_entry("vel", &[r.vel.x, r.vel.y, r.vel.z])?;
                    m.serialize_entry("vel_quat", &[q.i, q.j, q.k, q.w])?;
                    m.serialize_entry("vel_quat_dt", &r.vel_quat_dt)?;
                    m.serialize_entry("angular_velocity", &[w.x, w.y, w.z])
                })
            );
        } else {
            outln!(
                "Tracker {l}, sensor {}:\n     vel ({:5.2}, {:5.2}, {:5.2}); quatvel ({:5.2}, {:5.2}, {:5.2}, {:5.2}), dt {:5.2}",
                r.sensor, r.vel.x, r.vel.y, r.vel.z, q.i, q.j, q.k, q.w, r.vel_quat_dt
            );
        }
    });
    let (d, l, ck) = (device, label.to_owned(), clock.clone());
    let mut due = Stride::new(stride);
    tracker.on_acceleration(move |r| {
        if !due.take(r.sensor) {
            return;
        }
        let q = &r.acc_quat;
        if json {
            outln!(
                "{}",
                json_report(&d, "acceleration", Stamp { time: r.time, sender_time: r.sender_time }, &ck, |m| {
                    m.serialize_entry("sensor", &r.sensor)?;
                    m.serialize_entry("acc", &[r.acc.x, r.acc.y, r.acc.z])?;
                    m.serialize_entry("acc_quat", &[q.i, q.j, q.k, q.w])?;
                    m.serialize_entry("acc_quat_dt", &r.acc_quat_dt)
                })
            );
        } else {
            outln!(
                "Tracker {l}, sensor {}:\n     acc ({:5.2}, {:5.2}, {:5.2}); quatacc ({:5.2}, {:5.2}, {:5.2}, {:5.2}), dt {:5.2}",
                r.sensor, r.acc.x, r.acc.y, r.acc.z, q.i, q.j, q.k, q.w, r.acc_quat_dt
            );
        }
    });
}

/// Opens the Button, Analog, Dial and Text remotes of `name` beside its `tracker` and attaches
/// the printers (the C++ formats, or JSON objects of kind pose, velocity, acceleration, button,
/// button_states, analog, dial and text).
fn open_others(
    name: &str,
    tracker: TrackerRemote,
    json: bool,
    shown: Shown,
) -> Result<Opened, vrpn::Error> {
    let clock = ClockView::default();
    if shown.tracker {
        print_tracker(&tracker, name, json, &clock, shown.tracker_stride);
    }
    let button = ButtonRemote::new(name)?;
    let analog = AnalogRemote::new(name)?;
    let dial = DialRemote::new(name)?;
    let text = TextReceiver::new(name)?;
    if !shown.text {
        // Warnings and errors too (C++ removes the devices from its text printer).
        tracker.connection().mute_text_printer(tracker.sender());
    }
    let device = button.device().to_string();
    let label = name.to_string();
    let (dv, l, ck) = (device.clone(), label.clone(), clock.clone());
    let on = shown.button;
    button.on_change(move |c| {
        if !on {
            return;
        }
        if json {
            outln!(
                "{}",
                json_report(&dv, "button", Stamp { time: c.time, sender_time: c.sender_time }, &ck, |m| {
                    m.serialize_entry("button", &c.button)?;
                    m.serialize_entry("state", &c.state.raw())
                })
            );
        } else {
            let what = if c.state.is_pressed() { "pressed" } else { "released" };
            outln!(
                "##########################################\nButton {l}, number {} was just {what}\n##########################################",
                c.button
            );
        }
    });
    let (dv, l, ck) = (device.clone(), label.clone(), clock.clone());
    button.on_states(move |st| {
        if !on {
            return;
        }
        if json {
            outln!(
                "{}",
                json_report(
                    &dv,
                    "button_states",
                    Stamp {
                        time: st.time,
                        sender_time: st.sender_time
                    },
                    &ck,
                    |m| {
                        let raw: Vec<i32> = st.as_slice().iter().map(|b| b.raw()).collect();
                        m.serialize_entry("states", &raw)
                    }
                )
            );
        } else {
            let mut s = format!("Button {l} has {} buttons with states:", st.num_buttons);
            for v in st.as_slice() {
                let _ = write!(s, " {}", v.raw());
            }
            outln!("{s}");
        }
    });
    let (dv, l, ck) = (device.clone(), label.clone(), clock.clone());
    let on = shown.analog;
    analog.on_report(move |r| {
        if !on {
            return;
        }
        if json {
            outln!(
                "{}",
                json_report(
                    &dv,
                    "analog",
                    Stamp {
                        time: r.time,
                        sender_time: r.sender_time
                    },
                    &ck,
                    |m| { m.serialize_entry("channels", r.channels()) }
                )
            );
        } else {
            let mut s = format!("Analog {l}:\n         ");
            for (i, v) in r.channels().iter().enumerate() {
                if i > 0 {
                    s.push_str(", ");
                }
                let _ = write!(s, "{v:5.2}");
            }
            let _ = write!(s, " ({} chans)", r.num_channel);
            outln!("{s}");
        }
    });
    let (dv, l, ck) = (device.clone(), label.clone(), clock.clone());
    let on = shown.dial;
    dial.on_update(move |u| {
        if !on {
            return;
        }
        if json {
            outln!(
                "{}",
                json_report(
                    &dv,
                    "dial",
                    Stamp {
                        time: u.time,
                        sender_time: u.sender_time
                    },
                    &ck,
                    |m| {
                        m.serialize_entry("dial", &u.dial)?;
                        m.serialize_entry("change", &u.change)
                    }
                )
            );
        } else {
            outln!("Dial {l}, number {} was moved by {:5.2}", u.dial, u.change);
        }
    });
    let (dv, l, ck) = (device, label, clock.clone());
    let on = shown.text;
    text.on_message(move |msg| {
        if !on {
            return;
        }
        if json {
            let severity = match msg.severity {
                TextSeverity::Normal => "normal",
                TextSeverity::Warning => "warning",
                TextSeverity::Error => "error",
                TextSeverity::Other(_) => "other",
            };
            outln!(
                "{}",
                json_report(
                    &dv,
                    "text",
                    Stamp {
                        time: msg.time,
                        sender_time: msg.sender_time
                    },
                    &ck,
                    |m| {
                        m.serialize_entry("severity", severity)?;
                        m.serialize_entry("level", &msg.level)?;
                        m.serialize_entry("text", msg.text())
                    }
                )
            );
        } else {
            // Every severity here, on stdout with the reports (the default printer is off).
            let what = match msg.severity {
                TextSeverity::Normal => "Text message",
                TextSeverity::Warning => "Warning",
                TextSeverity::Error => "Error",
                TextSeverity::Other(_) => "Text",
            };
            outln!("{l}: {what}: {}", msg.text());
        }
    });
    Ok(Opened {
        name: name.to_string(),
        clock,
        json,
        tracker,
        button,
        analog,
        dial,
        text,
    })
}
