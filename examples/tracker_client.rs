//! The paper's "complete program": open a tracker, register a pose callback, call mainloop().
//!
//! Run a server first (`cargo run --release --bin vrpn_server -- -f vrpn.cfg.sample`), then:
//! `cargo run --example tracker_client -- Tracker0@localhost`

use std::time::Duration;

use vrpn::TrackerRemote;

fn main() -> Result<(), vrpn::Error> {
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "Tracker0@localhost".into());
    let tracker = TrackerRemote::new(&name)?;
    tracker.on_pose(|p| {
        println!(
            "sensor {}: pos ({:.3}, {:.3}, {:.3}) quat ({:.3}, {:.3}, {:.3}, {:.3})",
            p.sensor, p.pos.x, p.pos.y, p.pos.z, p.quat.i, p.quat.j, p.quat.k, p.quat.w
        );
    });
    loop {
        tracker.mainloop()?;
        // A renderer would draw a frame here; tracker.pose(0) holds the latest pose too.
        std::thread::sleep(Duration::from_millis(16));
    }
}
