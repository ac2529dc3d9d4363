//! vrpn_Tracker_WiimoteHead reports without allocating: the layered device over a Wiimote
//! Analog of the same server (`*Src`) and over one on another server (`Src@127.0.0.1:PORT`),
//! fed reports with two blobs, one, none and changing gravity, a client's tracker remote over
//! TCP. A counting global allocator covers every pass of the servers, the device and the
//! client once each has sent and heard its first reports.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::config::DeviceRef;
use vrpn::drivers::wiimote_head::{WiimoteHead, WiimoteHeadDevice};
use vrpn::net::Reactor;
use vrpn::ServerDevice;
use vrpn::{AnalogServer, Connection, Limits, Now, TimeVal, TrackerRemote};

struct Counting;

thread_local! {
    static ENABLED: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

fn note() {
    if ENABLED.try_with(Cell::get).unwrap_or(false) {
        let _ = COUNT.try_with(|c| c.set(c.get() + 1));
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        System.alloc(layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        System.realloc(ptr, layout, new_size)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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

/// Streams 300 Wiimote reports through a WiimoteHead over `source` and checks that no pass
/// allocates. `upstream` serves the Analog `Src` (the device's own server when local).
fn stream(local: bool) {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let reactor = Reactor::new().unwrap();
    let server =
        Connection::server_in(&reactor, Some(Ipv4Addr::LOCALHOST), 0, Limits::default()).unwrap();
    let upstream = if local {
        server.clone()
    } else {
        Connection::server_in(&reactor, Some(Ipv4Addr::LOCALHOST), 0, Limits::default()).unwrap()
    };
    let mut src = AnalogServer::new("Src", &upstream, 16).unwrap();
    let source = if local {
        DeviceRef::Local("Src".into())
    } else {
        DeviceRef::Remote(format!("Src@127.0.0.1:{}", upstream.local_port().unwrap()))
    };
    let cfg = WiimoteHead {
        name: "WH".into(),
        source,
        min_update_rate: 1.0,
        led_spacing: 0.145,
    };
    let mut device = WiimoteHeadDevice::new(&cfg, &server).unwrap();
    let client = Connection::client_in(
        &reactor,
        "127.0.0.1",
        server.local_port().unwrap(),
        false,
        Limits::default(),
    )
    .unwrap();
    let tracker = TrackerRemote::on_connection("WH", &client).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));

    let mut k = 0u32;
    let mut send = |src: &mut AnalogServer| {
        k += 1;
        wiimote_channels(k, src.channels_mut());
        src.report(Some(TimeVal::from_micros(
            1_700_000_000_000_000 + i64::from(k) * 10_000,
        )))
        .unwrap();
    };
    let mut pass = |counting: bool| {
        ENABLED.with(|e| e.set(counting));
        let _ = upstream.mainloop();
        device.mainloop(Now::read());
        let _ = server.mainloop();
        let _ = client.mainloop();
        ENABLED.with(|e| e.set(false));
        reactor
            .wait(device.next_deadline(), Duration::from_millis(1))
            .unwrap();
    };
    // Warm up: connect, hear the first reports.
    let start = Instant::now();
    while poses.get() < 30 {
        assert!(start.elapsed() < Duration::from_secs(20), "no poses");
        ENABLED.with(|e| e.set(false));
        send(&mut src);
        for _ in 0..5 {
            pass(false);
        }
    }
    let before = poses.get();
    COUNT.with(|c| c.set(0));
    for _ in 0..300 {
        ENABLED.with(|e| e.set(true));
        send(&mut src);
        ENABLED.with(|e| e.set(false));
        for _ in 0..3 {
            pass(true);
        }
    }
    let start = Instant::now();
    while poses.get() < before + 250 && start.elapsed() < Duration::from_secs(10) {
        pass(true);
    }
    assert!(
        poses.get() >= before + 250,
        "poses {before} → {}",
        poses.get()
    );
    assert_eq!(COUNT.with(Cell::get), 0, "allocations while streaming");
}

#[test]
fn wiimote_head_over_a_local_analog_reports_without_allocating() {
    stream(true);
}

#[test]
fn wiimote_head_over_a_remote_analog_reports_without_allocating() {
    stream(false);
}
