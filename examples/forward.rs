//! Re-serves one device's poses on another port (what C++ `forward` does with a
//! `vrpn_StreamForwarder`): a client of the device's server packs every `Tracker Pos_Quat` of
//! SERVICE on a server of its own at PORT (default 4510).
//!
//! `cargo run --example forward -- LOCATION SERVICE [PORT]`, e.g. `localhost:3883 Tracker0 4510`;
//! then read it with `vrpn_print_devices Tracker0@localhost:4510`.

use std::time::Duration;

use vrpn::forward::StreamForwarder;
use vrpn::{Connection, ServiceClass};

fn main() -> Result<(), vrpn::Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 || args.len() > 3 {
        eprintln!("usage: forward LOCATION SERVICE [PORT]");
        std::process::exit(2);
    }
    let port: u16 = args.get(2).and_then(|p| p.parse().ok()).unwrap_or(4510);
    let source = Connection::open(&format!("{}@{}", args[1], args[0]))?;
    let destination = Connection::server(None, port)?;
    let mut forwarder = StreamForwarder::new(&source, &args[1], &destination, &args[1])?;
    forwarder.forward(
        "vrpn_Tracker Pos_Quat",
        "vrpn_Tracker Pos_Quat",
        ServiceClass::RELIABLE,
    )?;
    eprintln!("forwarding Tracker Pos_Quat of {} on port {port}", args[1]);
    loop {
        source.mainloop()?;
        destination.mainloop()?;
        let _ = source.wait(Duration::from_millis(1));
    }
}
