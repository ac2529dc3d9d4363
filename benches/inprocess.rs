//! In-process delivery: a `TrackerServer` reporting on a loopback connection to a
//! `TrackerRemote` on_pose callback, and a raw `Connection::pack_message` to a registered
//! handler. Time per report = a batch of 1000 reports divided by 1000; median over batches.
//!
//! Baseline: the same work without the connection (encode the pose payload, decode it, call a
//! boxed callback through `Rc<RefCell<dyn FnMut>>`), so the ratio shows what the connection's
//! dispatch adds.

mod common;

use std::cell::{Cell, RefCell};
use std::hint::black_box;
use std::rc::Rc;

use vrpn::wire::class;
use vrpn::wire::payload::tracker::PosQuat;
use vrpn::{Connection, SenderFilter, TimeVal, TrackerRemote, TrackerServer};

const BATCH: usize = 1000;
const BATCHES: usize = 2000;
const TARGET_NS: u64 = 100;

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let t = TimeVal::now();
    let pos = [1.0, 2.0, 3.0];
    let quat = [0.0, 0.0, 0.0, 1.0];

    // Baseline: encode + decode + callback, no connection.
    let seen = Rc::new(Cell::new(0u64));
    let s = seen.clone();
    type Callback = Rc<RefCell<dyn FnMut(&PosQuat)>>;
    let cb: Callback = Rc::new(RefCell::new(move |_p: &PosQuat| s.set(s.get() + 1)));
    let baseline = common::run_batched(
        "baseline: encode+decode+callback",
        50,
        BATCHES,
        BATCH,
        || {
            let mut buf = [0u8; PosQuat::LEN];
            PosQuat {
                sensor: 0,
                pad: 0,
                pos: black_box(pos),
                quat: black_box(quat),
            }
            .encode(&mut buf);
            let p = PosQuat::decode(black_box(&buf)).unwrap();
            let f = cb.clone();
            (f.borrow_mut())(&p);
        },
    );

    // Tracker report → remote on_pose.
    let conn = Connection::new_loopback();
    let server = TrackerServer::new("Tracker0", &conn, 1).unwrap();
    let remote = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    remote.on_pose(move |_| p.set(p.get() + 1));
    remote.mainloop().unwrap();
    let tracker = common::run_batched("report_pose → on_pose", 50, BATCHES, BATCH, || {
        server.report_pose(0, t, black_box(pos), quat).unwrap();
    });
    assert_eq!(poses.get(), ((BATCHES + 50) * BATCH) as u64);

    // Raw pack_message → handler.
    let sender = conn.register_sender("bench").unwrap();
    let ty = conn.register_type("bench raw").unwrap();
    let raws = Rc::new(Cell::new(0u64));
    let r = raws.clone();
    conn.register_handler(ty, SenderFilter::Only(sender), move |m| {
        r.set(r.get() + m.payload.len() as u64)
    });
    let payload = [0u8; 64];
    let raw = common::run_batched(
        "pack_message → handler (64 B)",
        50,
        BATCHES,
        BATCH,
        || {
            conn.pack_message(t, ty, sender, black_box(&payload), class::LOW_LATENCY)
                .unwrap();
        },
    );
    assert_eq!(raws.get(), ((BATCHES + 50) * BATCH * 64) as u64);

    println!("in-process delivery, per report ({BATCHES} batches of {BATCH})");
    for s in [&baseline, &tracker, &raw] {
        s.print_ns();
    }
    for s in [&tracker, &raw] {
        let r = s.median() as f64 / baseline.median() as f64;
        let verdict = if s.median() <= TARGET_NS {
            "meets"
        } else {
            "MISSES"
        };
        println!(
            "    {}: p50 {} ns = {:.1}× baseline ({verdict} target ≤ {TARGET_NS} ns)",
            s.name,
            s.median(),
            r
        );
    }
}
