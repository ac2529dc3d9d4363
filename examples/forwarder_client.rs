//! Tells a server to open a port and forward message types of its devices there (what C++
//! `forwarderClient` does from its command prompt), with `vrpn::forward::ForwarderController`.
//!
//! `cargo run --example forwarder_client -- LOCATION PORT SERVICE TYPE [TYPE...]`, e.g.
//! `localhost:3883 4510 Tracker0 "vrpn_Tracker Pos_Quat"`. A server of this crate must allow
//! the port (`vrpn_server -forwardports 4510`); C++ `vrpn_server` opens any port.

use std::time::{Duration, Instant};

use vrpn::forward::ForwarderController;
use vrpn::Connection;

fn main() -> Result<(), vrpn::Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        eprintln!("usage: forwarder_client LOCATION PORT SERVICE TYPE [TYPE...]");
        std::process::exit(2);
    }
    let port: u16 = args[1].parse().expect("a port number");
    let conn = Connection::open(&format!("forwarder_client@{}", args[0]))?;
    let controller = ForwarderController::new(&conn)?;
    let start = Instant::now();
    while !conn.connected() {
        if start.elapsed() > Duration::from_secs(5) {
            eprintln!("no server at {}", args[0]);
            std::process::exit(1);
        }
        conn.mainloop()?;
        let _ = conn.wait(Duration::from_millis(10));
    }
    controller.start_remote_forwarding(port)?;
    for type_name in &args[3..] {
        controller.forward_message_type(port, &args[2], type_name)?;
        eprintln!(
            "asked to forward {type_name:?} of {} on port {port}",
            args[2]
        );
    }
    // Stay a moment so the requests go out, then leave (forwarding goes on without us).
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(500) {
        conn.mainloop()?;
        let _ = conn.wait(Duration::from_millis(10));
    }
    Ok(())
}
