//! vrpn_print_devices: opens each named device and prints every report, like the C++ tool;
//! `--json` prints one JSON object per line; `--list HOST[:PORT]` prints the device names a
//! server announces.

use std::cell::Cell;
use std::fmt::Write as _;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use vrpn::{
    AnalogRemote, ButtonRemote, Connection, ConnectionState, DeviceName, DialRemote, TextReceiver,
    TextSeverity, TrackerRemote,
};

const USAGE: &str =
    "usage: vrpn_print_devices [--json] [--seconds S] [--log FILE] DEVICE@HOST[:PORT]...
       vrpn_print_devices --list HOST[:PORT]
  DEVICE@HOST        e.g. Tracker0@localhost, Tracker0@tcp://host:3883, Tracker0@host:3884
  --json             one JSON object per report: device, kind, time, and the values
  --seconds S        exit after S seconds (default: run until interrupted)
  --log FILE         log every message received to FILE (C++ .vrpn format; one file per
                     server: FILE-2.vrpn, … for the second and later); replay it with
                     DEVICE@file:FILE
  --list HOST[:PORT] print the device names the server announces, then exit";

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

/// Formats an f64 as JSON (null for NaN and infinities).
fn num(out: &mut String, v: f64) {
    if v.is_finite() {
        let _ = write!(out, "{v:?}");
    } else {
        out.push_str("null");
    }
}

fn arr(out: &mut String, vals: &[f64]) {
    out.push('[');
    for (i, v) in vals.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        num(out, *v);
    }
    out.push(']');
}

fn json_str(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

fn head(device: &str, kind: &str, time: vrpn::TimeVal) -> String {
    let mut s = String::with_capacity(200);
    s.push_str("{\"device\":");
    json_str(&mut s, device);
    s.push_str(",\"kind\":\"");
    s.push_str(kind);
    s.push_str("\",\"time\":");
    num(&mut s, time.as_secs_f64());
    s
}

fn list(location: &str) -> i32 {
    let name = format!("vrpn_print_devices@{location}");
    let conn = match Connection::open(&name) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("vrpn_print_devices: {e}");
            return 2;
        }
    };
    let start = Instant::now();
    let mut connected_at = None;
    while start.elapsed() < Duration::from_secs(10) && !STOP.load(Ordering::Relaxed) {
        let _ = conn.mainloop();
        if conn.state() == ConnectionState::Connected && connected_at.is_none() {
            connected_at = Some(Instant::now());
        }
        // Descriptions arrive right after the cookie; give late ones a moment.
        if connected_at.is_some_and(|t| t.elapsed() > Duration::from_millis(300)) {
            for s in conn.peer_senders() {
                if s != "VRPN Control" && s != "vrpn_Forwarder_Brain" && s != "vrpn_print_devices" {
                    println!("{s}");
                }
            }
            return 0;
        }
        let _ = conn.wait(Duration::from_millis(10));
    }
    eprintln!("vrpn_print_devices: no VRPN server answered at {location} within 10 s");
    1
}

fn main() {
    let mut json = false;
    let mut log: Option<String> = None;
    let mut seconds: Option<f64> = None;
    let mut names = Vec::new();
    let mut args = std::env::args().skip(1);
    install_signal_handlers();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--json" => json = true,
            "--log" => match args.next() {
                Some(f) => log = Some(f),
                None => {
                    eprintln!("--log needs a file name\n{USAGE}");
                    std::process::exit(2);
                }
            },
            "--seconds" => {
                seconds = args.next().and_then(|s| s.parse().ok());
                if seconds.is_none() {
                    eprintln!("--seconds needs a number\n{USAGE}");
                    std::process::exit(2);
                }
            }
            "--list" => match args.next() {
                Some(loc) => std::process::exit(list(&loc)),
                None => {
                    eprintln!("--list needs HOST[:PORT]\n{USAGE}");
                    std::process::exit(2);
                }
            },
            "-h" | "--help" => {
                println!("{USAGE}");
                return;
            }
            s if s.starts_with("--") => {
                eprintln!("unknown option {s}\n{USAGE}");
                std::process::exit(2);
            }
            s => names.push(s.to_string()),
        }
    }
    if names.is_empty() {
        eprintln!("{USAGE}");
        std::process::exit(2);
    }
    let mut trackers = Vec::new();
    let mut logged: Vec<Connection> = Vec::new();
    let printed = Rc::new(Cell::new(0u64));
    for name in &names {
        if let Err(e) = DeviceName::parse(name) {
            eprintln!("vrpn_print_devices: {e}");
            std::process::exit(2);
        }
        let t = match TrackerRemote::new(name) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("vrpn_print_devices: {name}: {e}");
                std::process::exit(2);
            }
        };
        if let Some(path) = &log {
            let conn = t.connection();
            if !logged.iter().any(|c: &Connection| c.same_as(conn)) {
                let file = match logged.len() {
                    0 => path.clone(),
                    n => match path.rfind('.') {
                        Some(i) => format!("{}-{}{}", &path[..i], n + 1, &path[i..]),
                        None => format!("{path}-{}", n + 1),
                    },
                };
                if let Err(e) = conn.log_incoming(&file) {
                    eprintln!("vrpn_print_devices: --log {file}: {e}");
                    std::process::exit(2);
                }
                logged.push(conn.clone());
            }
        }
        let label = name.clone();
        let device = t.device().to_string();
        let p = printed.clone();
        if json {
            let d = device.clone();
            t.on_pose(move |r| {
                let mut s = head(&d, "pose", r.time);
                let _ = write!(s, ",\"sensor\":{},\"pos\":", r.sensor);
                arr(&mut s, &[r.pos.x, r.pos.y, r.pos.z]);
                s.push_str(",\"quat\":");
                arr(&mut s, &[r.quat.i, r.quat.j, r.quat.k, r.quat.w]);
                s.push('}');
                println!("{s}");
                p.set(p.get() + 1);
            });
            let d = device.clone();
            let p = printed.clone();
            t.on_velocity(move |r| {
                let mut s = head(&d, "velocity", r.time);
                let _ = write!(s, ",\"sensor\":{},\"vel\":", r.sensor);
                arr(&mut s, &[r.vel.x, r.vel.y, r.vel.z]);
                s.push_str(",\"vel_quat\":");
                let q = &r.vel_quat;
                arr(&mut s, &[q.i, q.j, q.k, q.w]);
                s.push_str(",\"vel_quat_dt\":");
                num(&mut s, r.vel_quat_dt);
                let w = r.angular_velocity();
                s.push_str(",\"angular_velocity\":");
                arr(&mut s, &[w.x, w.y, w.z]);
                s.push('}');
                println!("{s}");
                p.set(p.get() + 1);
            });
            let d = device;
            let p = printed.clone();
            t.on_acceleration(move |r| {
                let mut s = head(&d, "acceleration", r.time);
                let _ = write!(s, ",\"sensor\":{},\"acc\":", r.sensor);
                arr(&mut s, &[r.acc.x, r.acc.y, r.acc.z]);
                s.push_str(",\"acc_quat\":");
                let q = &r.acc_quat;
                arr(&mut s, &[q.i, q.j, q.k, q.w]);
                s.push_str(",\"acc_quat_dt\":");
                num(&mut s, r.acc_quat_dt);
                s.push('}');
                println!("{s}");
                p.set(p.get() + 1);
            });
        } else {
            let l = label.clone();
            t.on_pose(move |r| {
                println!(
                    "Tracker {l}, sensor {}:\n     pos ({:5.2}, {:5.2}, {:5.2}); quat ({:5.2}, {:5.2}, {:5.2}, {:5.2})",
                    r.sensor, r.pos.x, r.pos.y, r.pos.z, r.quat.i, r.quat.j, r.quat.k, r.quat.w
                );
                p.set(p.get() + 1);
            });
            let l = label.clone();
            let p = printed.clone();
            t.on_velocity(move |r| {
                let q = &r.vel_quat;
                println!(
                    "Tracker {l}, sensor {}:\n     vel ({:5.2}, {:5.2}, {:5.2}); quatvel ({:5.2}, {:5.2}, {:5.2}, {:5.2}), dt {:5.2}",
                    r.sensor, r.vel.x, r.vel.y, r.vel.z, q.i, q.j, q.k, q.w, r.vel_quat_dt
                );
                p.set(p.get() + 1);
            });
            let l = label;
            let p = printed.clone();
            t.on_acceleration(move |r| {
                let q = &r.acc_quat;
                println!(
                    "Tracker {l}, sensor {}:\n     acc ({:5.2}, {:5.2}, {:5.2}); quatacc ({:5.2}, {:5.2}, {:5.2}, {:5.2}), dt {:5.2}",
                    r.sensor, r.acc.x, r.acc.y, r.acc.z, q.i, q.j, q.k, q.w, r.acc_quat_dt
                );
                p.set(p.get() + 1);
            });
        }
        let others = match open_others(name, json, &printed) {
            Ok(o) => o,
            Err(e) => {
                eprintln!("vrpn_print_devices: {name}: {e}");
                std::process::exit(2);
            }
        };
        if !json {
            println!("Opened {name} as: Tracker Button Analog Dial Text.");
        }
        trackers.push((t, others));
    }
    if !json {
        println!("Press ^C to exit.");
    }
    let start = Instant::now();
    while !STOP.load(Ordering::Relaxed) {
        if seconds.is_some_and(|s| start.elapsed().as_secs_f64() >= s) {
            break;
        }
        for (t, o) in &trackers {
            if let Err(e) = t
                .mainloop()
                .and_then(|_| o.0.mainloop())
                .and_then(|_| o.1.mainloop())
                .and_then(|_| o.2.mainloop())
                .and_then(|_| o.3.mainloop())
            {
                eprintln!("vrpn_print_devices: {e}");
                std::process::exit(1);
            }
        }
        // Sleep until data arrives (or 10 ms for ping timers and reconnect attempts).
        if let Some((t, _)) = trackers.first() {
            let _ = t.connection().wait(Duration::from_millis(10));
        }
    }
}

type Others = (ButtonRemote, AnalogRemote, DialRemote, TextReceiver);

/// Opens the Button, Analog, Dial and Text remotes of `name` and attaches the printers (the
/// C++ formats, or JSON objects of kind button, button_states, analog, dial and text).
fn open_others(name: &str, json: bool, printed: &Rc<Cell<u64>>) -> Result<Others, vrpn::Error> {
    let b = ButtonRemote::new(name)?;
    let a = AnalogRemote::new(name)?;
    let d = DialRemote::new(name)?;
    let t = TextReceiver::new(name)?;
    let device = b.device().to_string();
    let label = name.to_string();
    let (dv, p) = (device.clone(), printed.clone());
    let l = label.clone();
    b.on_change(move |c| {
        if json {
            let mut s = head(&dv, "button", c.time);
            let _ = write!(s, ",\"button\":{},\"state\":{}}}", c.button, c.state);
            println!("{s}");
        } else {
            let what = if c.state != 0 { "pressed" } else { "released" };
            println!(
                "##########################################\nButton {l}, number {} was just {what}\n##########################################",
                c.button
            );
        }
        p.set(p.get() + 1);
    });
    let (dv, p) = (device.clone(), printed.clone());
    let l = label.clone();
    b.on_states(move |st| {
        if json {
            let mut s = head(&dv, "button_states", st.time);
            s.push_str(",\"states\":[");
            for (i, v) in st.as_slice().iter().enumerate() {
                if i > 0 {
                    s.push(',');
                }
                let _ = write!(s, "{v}");
            }
            s.push_str("]}");
            println!("{s}");
        } else {
            let mut s = format!("Button {l} has {} buttons with states:", st.num_buttons);
            for v in st.as_slice() {
                let _ = write!(s, " {v}");
            }
            println!("{s}");
        }
        p.set(p.get() + 1);
    });
    let (dv, p) = (device.clone(), printed.clone());
    let l = label.clone();
    a.on_report(move |r| {
        if json {
            let mut s = head(&dv, "analog", r.time);
            s.push_str(",\"channels\":");
            arr(&mut s, r.channels());
            s.push('}');
            println!("{s}");
        } else {
            let mut s = format!("Analog {l}:\n         ");
            for (i, v) in r.channels().iter().enumerate() {
                if i > 0 {
                    s.push_str(", ");
                }
                let _ = write!(s, "{v:5.2}");
            }
            let _ = write!(s, " ({} chans)", r.num_channel);
            println!("{s}");
        }
        p.set(p.get() + 1);
    });
    let (dv, p) = (device.clone(), printed.clone());
    let l = label.clone();
    d.on_update(move |u| {
        if json {
            let mut s = head(&dv, "dial", u.time);
            let _ = write!(s, ",\"dial\":{},\"change\":", u.dial);
            num(&mut s, u.change);
            s.push('}');
            println!("{s}");
        } else {
            println!("Dial {l}, number {} was moved by {:5.2}", u.dial, u.change);
        }
        p.set(p.get() + 1);
    });
    let (dv, p) = (device, printed.clone());
    let l = label;
    t.on_message(move |m| {
        if json {
            let mut s = head(&dv, "text", m.time);
            let sev = match m.severity {
                TextSeverity::Normal => "normal",
                TextSeverity::Warning => "warning",
                TextSeverity::Error => "error",
                TextSeverity::Other(_) => "other",
            };
            let _ = write!(s, ",\"severity\":\"{sev}\",\"level\":{},\"text\":", m.level);
            json_str(&mut s, m.text());
            s.push('}');
            println!("{s}");
        } else if m.severity == TextSeverity::Normal {
            // Warnings and errors are printed by the default text printer.
            println!("{l}: Text message: {}", m.text());
        }
        p.set(p.get() + 1);
    });
    Ok((b, a, d, t))
}
