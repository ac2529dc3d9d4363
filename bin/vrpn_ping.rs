//! vrpn_ping: measures the user-level round trip (ping to pong) to any VRPN server, C++ or ours.

use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::base::{PING_MESSAGE, PONG_MESSAGE};
use vrpn::wire::class;
use vrpn::{Connection, DeviceName, SenderFilter, TimeVal};

const USAGE: &str = "usage: vrpn_ping DEVICE@HOST[:PORT] [-n COUNT]
  Sends COUNT pings (default 1000) to DEVICE and prints the round-trip p50/p99/max in µs.
  The server answers pings only for devices it has, so DEVICE must exist there.";

fn main() {
    let mut count = 1000usize;
    let mut name = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "-n" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) if n > 0 => count = n,
                _ => {
                    eprintln!("-n needs a positive count\n{USAGE}");
                    std::process::exit(2);
                }
            },
            "-h" | "--help" => {
                println!("{USAGE}");
                return;
            }
            s if name.is_none() && !s.starts_with('-') => name = Some(s.to_string()),
            s => {
                eprintln!("unexpected argument {s:?}\n{USAGE}");
                std::process::exit(2);
            }
        }
    }
    let Some(name) = name else {
        eprintln!("{USAGE}");
        std::process::exit(2);
    };
    match run(&name, count) {
        Ok(mut rtts) => {
            rtts.sort_unstable_by(f64::total_cmp);
            let pct = |p: f64| rtts[((rtts.len() - 1) as f64 * p).round() as usize];
            println!(
                "{} pings to {name}: p50 {:.1} µs  p99 {:.1} µs  max {:.1} µs",
                rtts.len(),
                pct(0.5),
                pct(0.99),
                rtts[rtts.len() - 1]
            );
        }
        Err(e) => {
            eprintln!("vrpn_ping: {e}");
            std::process::exit(1);
        }
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
    let start = Instant::now();
    while !conn.connected() {
        if start.elapsed() > Duration::from_secs(10) {
            return Err(format!("could not connect to {name} within 10 s"));
        }
        conn.mainloop().map_err(|e| e.to_string())?;
        let _ = conn.wait(Duration::from_millis(5));
    }
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
            if t0.elapsed() > Duration::from_secs(2) {
                return Err(format!(
                    "ping {i} got no pong within 2 s: does {} exist on that server?",
                    parsed.device
                ));
            }
        }
        rtts.push(t0.elapsed().as_secs_f64() * 1e6);
    }
    Ok(rtts)
}
