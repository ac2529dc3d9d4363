//! vrpn_Tracker_WiimoteHead reports without allocating: the layered device over a Wiimote
//! Analog of the same server (`*Src`) and over one on another server (`Src@127.0.0.1:PORT`),
//! fed reports with two blobs, one, none and changing gravity, a client's tracker remote over
//! TCP. A counting global allocator covers every pass of the servers, the device and the
//! client once each has sent and heard its first reports.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
#[path = "common/layered_rig.rs"]
mod layered_rig;

use std::cell::Cell;
use std::rc::Rc;

use counting_alloc::{count, counter_works};
use layered_rig::Layered;
use vrpn::drivers::wiimote_head::{WiimoteHead, WiimoteHeadDevice};
use vrpn::{AnalogServer, TimeVal, TrackerRemote};

/// Report `k` of the Wiimote: gravity that changes every seventh report, two blobs mostly.
fn wiimote_channels(k: u32, out: &mut [f64]) {
    out.fill(0.0);
    let f = f64::from(k % 97);
    out[1] = if k % 7 == 0 { 0.01 * f } else { 0.0 };
    out[2] = 1.0;
    out[3] = 0.1;
    let blobs = match k % 10 {
        3 => 1,
        6 => 0,
        _ => 2,
    };
    for b in 0..blobs {
        out[4 + 3 * b] = 200.0 + 5.0 * f + 300.0 * b as f64;
        out[5 + 3 * b] = 300.0 + 2.0 * f;
        out[6 + 3 * b] = 2.0;
    }
}

/// Streams 300 Wiimote reports through a WiimoteHead over `Src` and checks that no pass
/// allocates. `local`: `Src` is served by the device's own server.
fn stream(local: bool) {
    let rig = Layered::new(local);
    let mut src = AnalogServer::new("Src", &rig.upstream, 16).unwrap();
    let cfg = WiimoteHead {
        name: "WH".into(),
        source: rig.source("Src"),
        min_update_rate: 1.0,
        led_spacing: 0.145,
    };
    let mut device = WiimoteHeadDevice::new(&cfg, &rig.server).unwrap();
    let client = rig.client();
    let tracker = TrackerRemote::on_connection("WH", &client).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));

    let mut k = 0u32;
    let mut send = || {
        k += 1;
        wiimote_channels(k, src.channels_mut());
        src.report(Some(TimeVal::from_micros(
            1_700_000_000_000_000 + i64::from(k) * 10_000,
        )))
        .unwrap();
    };
    // Warm up: connect, hear the first reports.
    rig.warm_up(
        &mut device,
        &client,
        &mut send,
        || poses.get() >= 30,
        "no poses",
    );
    let before = poses.get();
    rig.stream(&mut device, &client, 300, &mut send, || {
        poses.get() >= before + 250
    });
    assert!(
        poses.get() >= before + 250,
        "poses {before} → {}",
        poses.get()
    );
    assert_eq!(count(), 0, "allocations while streaming");
    counter_works();
}

#[test]
fn wiimote_head_over_a_local_analog_reports_without_allocating() {
    stream(true);
}

#[test]
fn wiimote_head_over_a_remote_analog_reports_without_allocating() {
    stream(false);
}
