//! Log replay (`Device@file:...`) of real C++ logs and of our own, and client-side logging
//! across a server restart.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use serde_json::Value;
use vrpn::devices::analog::AnalogRemote;
use vrpn::devices::button::ButtonRemote;
use vrpn::devices::dial::DialRemote;
use vrpn::log::LogReader;
use vrpn::{Connection, ConnectionEvent, ServerDevice, TrackerNull, TrackerRemote};

fn fixture(name: &str) -> String {
    format!(
        "{}/tests/fixtures/golden/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// The type ids of a log's whole entries, in order (up to any damage).
fn type_ids(log: &LogReader) -> Vec<i32> {
    let mut out = Vec::new();
    let mut entries = log.entries();
    while let Some(Ok(e)) = entries.next_entry() {
        out.push(e.type_id());
    }
    out
}

fn expected(name: &str) -> Value {
    serde_json::from_slice(&std::fs::read(fixture(&format!("{name}.expected.json"))).unwrap())
        .unwrap()
}

fn tmp(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("vrpn-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    let _ = std::fs::remove_file(&p);
    p.to_str().unwrap().to_string()
}

/// Replays the golden client log at `rate`; returns (wall seconds from first to last pose,
/// pose times delivered).
fn replay_client_log(rate: f64) -> (f64, Vec<(i64, i64)>) {
    // A private connection per run (names are shared per location text otherwise).
    let conn = Connection::replay_file(&fixture("tracker_client_log.client_in.vrpn")).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    conn.replay().unwrap().set_rate(rate);
    let times = Rc::new(RefCell::new(Vec::new()));
    let first_last = Rc::new(Cell::new((None::<Instant>, None::<Instant>)));
    let (t, fl) = (times.clone(), first_last.clone());
    tracker.on_pose(move |p| {
        t.borrow_mut().push((p.time.sec, p.time.usec));
        let (f, _) = fl.get();
        fl.set((f.or(Some(Instant::now())), Some(Instant::now())));
    });
    let start = Instant::now();
    while !conn.replay().unwrap().eof() && start.elapsed() < Duration::from_secs(20) {
        tracker.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(200));
    }
    let (f, l) = first_last.get();
    let wall = l.unwrap().duration_since(f.unwrap()).as_secs_f64();
    let times = times.borrow().clone();
    (wall, times)
}

#[test]
fn cpp_client_log_replays_at_the_original_pace_with_original_timestamps() {
    let exp = expected("tracker_client_log.client_in.vrpn");
    let poses: Vec<(i64, i64)> = exp["entries"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["type"] == "vrpn_Tracker Pos_Quat")
        .map(|e| (e["sec"].as_i64().unwrap(), e["usec"].as_i64().unwrap()))
        .collect();
    let span = (poses.last().unwrap().0 - poses[0].0) as f64
        + (poses.last().unwrap().1 - poses[0].1) as f64 * 1e-6;
    let (wall, times) = replay_client_log(1.0);
    assert_eq!(times, poses, "timestamps must be the recorded ones");
    assert!(
        (wall - span).abs() <= span * 0.05,
        "rate 1: {wall:.3} s for a {span:.3} s log"
    );
    let (wall10, times10) = replay_client_log(10.0);
    assert_eq!(times10.len(), poses.len());
    eprintln!("replay pace: {span:.3} s log took {wall:.3} s at rate 1, {wall10:.4} s at rate 10");
    // 5%, plus 10 ms for scheduling jitter on a loaded 2-core machine.
    assert!(
        (wall10 - span / 10.0).abs() <= span / 10.0 * 0.05 + 0.010,
        "rate 10: {wall10:.4} s for a {span:.3} s log"
    );
}

#[test]
fn controls_reset_play_to_jump_and_times() {
    let conn = Connection::replay_file(&fixture("tracker_udp_lob.out.vrpn")).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let n = Rc::new(Cell::new(0u32));
    let c = n.clone();
    tracker.on_pose(move |_| c.set(c.get() + 1));
    let drops = Rc::new(Cell::new(0));
    let d = drops.clone();
    conn.on_event(ConnectionEvent::DroppedConnection, move || {
        d.set(d.get() + 1)
    });
    let r = conn.replay().unwrap();
    let (first, last) = (r.first_time().unwrap(), r.last_time().unwrap());
    assert!((r.length_secs() - last.seconds_since(first)).abs() < 1e-9);
    assert!(r.length_secs() > 3.0);
    r.set_rate(0.0);
    tracker.mainloop().unwrap();
    tracker.mainloop().unwrap();
    assert_eq!(n.get(), 0, "paused replay plays nothing");
    r.play_to_time(1.0);
    let at_one = n.get();
    assert!(at_one > 50, "{at_one}");
    assert!((r.elapsed() - 1.0).abs() < 1e-6);
    // Two sensors at ~120 Hz over the first second: poses up to then, none after.
    r.play_to_time(r.length_secs() + 1.0);
    assert_eq!(n.get(), 410);
    assert!(r.eof());
    r.reset();
    assert_eq!(drops.get(), 1);
    assert!(!r.eof());
    n.set(0);
    assert!(r.jump_to_time(2.0));
    assert_eq!(n.get(), 0, "a jump delivers nothing");
    r.play_to_time(r.length_secs() + 1.0);
    let after_jump = n.get();
    assert!(after_jump > 100 && after_jump < 300, "{after_jump}");
    // Descriptions passed over by the jump were still learned: poses decode after it.
    assert_eq!(tracker.bad_messages(), 0);
    r.reset();
    let mut steps = 0;
    while r.play_one() {
        steps += 1;
    }
    assert!(steps > 1000);
}

#[test]
fn several_devices_of_every_logged_type_in_one_log() {
    let name = fixture("button_analog_dial.out.vrpn");
    let loc = format!("file:{name}");
    let buttons = ButtonRemote::new(&format!("Button0@{loc}")).unwrap();
    let analog = AnalogRemote::new(&format!("Analog0@{loc}")).unwrap();
    let dial = DialRemote::new(&format!("Dial0@{loc}")).unwrap();
    assert!(buttons.connection().same_as(analog.connection()));
    let counts = Rc::new(RefCell::new([0u32; 3]));
    let c = counts.clone();
    buttons.on_change(move |_| c.borrow_mut()[0] += 1);
    let c = counts.clone();
    analog.on_report(move |_| c.borrow_mut()[1] += 1);
    let c = counts.clone();
    dial.on_update(move |u| {
        assert_eq!(u.change, 0.1);
        c.borrow_mut()[2] += 1
    });
    let r = buttons.connection().replay().unwrap();
    r.set_rate(f64::INFINITY);
    let start = Instant::now();
    while !r.eof() && start.elapsed() < Duration::from_secs(10) {
        buttons.mainloop().unwrap();
    }
    let exp = expected("button_analog_dial.out.vrpn");
    let count = |t: &str| {
        exp["entries"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["type"] == t)
            .count() as u32
    };
    let got = *counts.borrow();
    assert_eq!(got[1], count("vrpn_Analog Channel"));
    assert_eq!(got[2], count("vrpn_Dial update"));
    // Button0's changes only (Analog0 also exports a button interface in that capture).
    assert!(got[0] > 0 && got[0] <= count("vrpn_Button Change"));
}

#[test]
fn truncated_log_plays_every_whole_message_then_says_where() {
    let bytes = std::fs::read(fixture("tracker_udp_lob.out.vrpn")).unwrap();
    let cut = bytes.len() - 30;
    let path = tmp("truncated.vrpn");
    std::fs::write(&path, &bytes[..cut]).unwrap();
    let whole = type_ids(&LogReader::open(&path).unwrap())
        .iter()
        .filter(|&&t| t == 4)
        .count();
    let conn = Connection::replay_file(&path).unwrap();
    let notices = Rc::new(RefCell::new(Vec::new()));
    let ns = notices.clone();
    conn.on_notice(move |n| ns.borrow_mut().push(n.text.clone()));
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let n = Rc::new(Cell::new(0usize));
    let c = n.clone();
    tracker.on_pose(move |_| c.set(c.get() + 1));
    conn.replay().unwrap().play_to_time(1e6);
    assert_eq!(n.get(), whole);
    let text = notices.borrow().join("\n");
    assert!(
        text.contains("truncated.vrpn") && text.contains("byte"),
        "{text}"
    );
}

#[test]
fn client_log_survives_a_server_restart_and_holds_every_received_message() {
    let path = tmp("client_in.vrpn");
    let out_path = tmp("client_out.vrpn");
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let mut null = TrackerNull::new("Tracker0", &server, 2, 200.0).unwrap();
    let conn = Connection::client("127.0.0.1", port, true, vrpn::Limits::default()).unwrap();
    conn.log_incoming(&path).unwrap();
    conn.log_outgoing(&out_path).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let received = Rc::new(Cell::new(0usize));
    let c = received.clone();
    tracker.on_pose(move |_| c.set(c.get() + 1));
    let run = |null: &mut TrackerNull, server: &Connection, until: usize| {
        let start = Instant::now();
        while received.get() < until && start.elapsed() < Duration::from_secs(10) {
            null.mainloop(vrpn::Now::read());
            server.mainloop().unwrap();
            tracker.mainloop().unwrap();
            std::thread::sleep(Duration::from_micros(300));
        }
    };
    run(&mut null, &server, 50);
    drop(null);
    drop(server);
    // The client notices and keeps logging into the same file after the restart.
    let start = Instant::now();
    while conn.connected() && start.elapsed() < Duration::from_secs(5) {
        tracker.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), port).unwrap();
    let mut null = TrackerNull::new("Tracker0", &server, 2, 200.0).unwrap();
    let before = received.get();
    run(&mut null, &server, before + 50);
    drop(tracker);
    conn.close_logs().unwrap();
    let reader = LogReader::open(&path).unwrap();
    assert_eq!(&reader.cookie_bytes()[..16], b"vrpn: ver. 07.38");
    let mut names = vrpn::log::NameTable::new();
    let mut logged = 0;
    let mut entries = reader.entries();
    while let Some(e) = entries.next_entry() {
        let e = e.unwrap();
        let _ = names.observe(&e);
        if e.type_id() >= 0 && names.type_name(e.type_id()) == Some("vrpn_Tracker Pos_Quat") {
            logged += 1;
        }
    }
    assert_eq!(logged, received.get(), "every received pose is in the log");
    // The outgoing log has our descriptions for both sessions and a DISCONNECT between.
    let out = LogReader::open(&out_path).unwrap();
    let disconnects = type_ids(&out).iter().filter(|&&t| t == -5).count();
    assert!(disconnects >= 1);
    // Our client log replays through our reader exactly as received.
    let replay = Connection::replay_file(&path).unwrap();
    let t2 = TrackerRemote::on_connection("Tracker0", &replay).unwrap();
    let n = Rc::new(Cell::new(0usize));
    let c = n.clone();
    t2.on_pose(move |_| c.set(c.get() + 1));
    replay.replay().unwrap().play_to_time(1e6);
    assert_eq!(n.get(), received.get());
}

#[test]
fn server_logs_outgoing_from_start_and_incoming_per_client() {
    let out = tmp("server_out.vrpn");
    let inc = tmp("server_in.vrpn");
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    server.log_outgoing(&out).unwrap();
    server.log_incoming(&inc).unwrap();
    let port = server.local_port().unwrap();
    let mut null = TrackerNull::new("Tracker0", &server, 1, 500.0).unwrap();
    // Reports from before any client connects are logged too.
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(50) {
        null.mainloop(vrpn::Now::read());
        server.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    let client = TrackerRemote::new(&format!("Tracker0@tcp://127.0.0.1:{port}")).unwrap();
    let start = Instant::now();
    while client.ping_cycle().last_pong().is_none() && start.elapsed() < Duration::from_secs(10) {
        null.mainloop(vrpn::Now::read());
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(300));
    }
    drop(client);
    drop(null);
    server.close_logs().unwrap();
    let out_log = LogReader::open(&out).unwrap();
    let types = type_ids(&out_log);
    assert!(types.iter().filter(|&&t| t >= 0).count() > 20);
    assert_eq!(*types.last().unwrap(), -5, "ends with DISCONNECT");
    let in_name = inc.replace(".vrpn", "-1.vrpn");
    let in_log = LogReader::open(&in_name).unwrap();
    let mut names = vrpn::log::NameTable::new();
    let mut pings = 0;
    let mut entries = in_log.entries();
    while let Some(e) = entries.next_entry() {
        let e = e.unwrap();
        let _ = names.observe(&e);
        if names.type_name(e.type_id()) == Some("vrpn_Base ping_message") {
            pings += 1;
        }
    }
    assert!(
        pings >= 1,
        "the client's ping is in the per-client incoming log"
    );
}

/// What a control called from inside a pose callback did, for one control.
struct InCallback {
    /// Times (µs since the first pose) of the poses delivered, in order.
    poses: Vec<i64>,
    /// Dropped-connection events (a reset fires one).
    drops: u32,
    /// `elapsed()` after the outside call returned.
    elapsed: f64,
}

/// Replays the golden tracker log paused, asks to play the first second from outside, and
/// calls `control` from inside the 10th pose callback (issue 29, item 1: this panicked and
/// broke the remote for good). Then plays the rest from outside.
fn control_in_callback(control: &'static str) -> InCallback {
    let conn = Connection::replay_file(&fixture("tracker_udp_lob.out.vrpn")).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let r = conn.replay().unwrap();
    let first = r.first_time().unwrap();
    let poses = Rc::new(RefCell::new(Vec::new()));
    let drops = Rc::new(Cell::new(0u32));
    let d = drops.clone();
    conn.on_event(ConnectionEvent::DroppedConnection, move || {
        d.set(d.get() + 1)
    });
    let (p, weak) = (poses.clone(), conn.downgrade());
    tracker.on_pose(move |pose| {
        let n = {
            let mut p = p.borrow_mut();
            p.push(((pose.time.seconds_since(first)) * 1e6).round() as i64);
            p.len()
        };
        if n != 10 {
            return;
        }
        let conn = weak.upgrade().unwrap();
        let r = conn.replay().unwrap();
        // Every query works from a callback too.
        assert!(!r.eof() && r.elapsed() < 1.0 && r.length_secs() > 3.0);
        assert!(r.first_time().is_some() && r.last_time().is_some());
        let _ = (r.file_time(), r.rate());
        match control {
            "set_rate" => r.set_rate(f64::INFINITY),
            "reset" => r.reset(),
            "play_to_time" => r.play_to_time(2.0),
            "play_one" => assert!(r.play_one()),
            "jump_to_time" => assert!(r.jump_to_time(2.0)),
            "mainloop" => conn.mainloop().unwrap(),
            other => panic!("{other}"),
        }
    });
    r.set_rate(0.0);
    r.play_to_time(1.0);
    let elapsed = r.elapsed();
    let before_rest = poses.borrow().len();
    // The remote still works: everything after plays from outside, in order.
    r.play_to_time(r.length_secs() + 1.0);
    assert!(r.eof(), "{control}: not at the end");
    assert!(
        poses.borrow().len() > before_rest,
        "{control}: nothing played after"
    );
    assert_eq!(tracker.bad_messages(), 0, "{control}");
    let poses = poses.borrow().clone();
    InCallback {
        poses,
        drops: drops.get(),
        elapsed,
    }
}

#[test]
fn every_replay_control_is_safe_from_inside_a_callback() {
    // The reference: the log played in order, in one go, from outside.
    let all = control_in_callback("mainloop").poses;
    assert_eq!(all.len(), 410);
    let up_to = |secs: f64| all.iter().filter(|&&t| t as f64 <= secs * 1e6).count();
    let sorted = |v: &[i64]| v.windows(2).all(|w| w[0] <= w[1]);

    // A rate change takes effect at once; the paused play-to still ends at 1 s.
    let r = control_in_callback("set_rate");
    assert_eq!(r.poses, all, "set_rate");
    assert!((r.elapsed - 1.0).abs() < 1e-6, "{}", r.elapsed);

    // Reset: back to the start when the callback returns (a dropped-connection event, as in
    // C++); the rest of the play-to is dropped with the old position, so the outside
    // play-to then plays the whole log again.
    let r = control_in_callback("reset");
    assert_eq!(r.drops, 1);
    assert_eq!(&r.poses[..10], &all[..10]);
    assert_eq!(&r.poses[10..], &all[..], "reset");

    // Play-to from the callback replaces the running one: up to 2 s, then the rest.
    let r = control_in_callback("play_to_time");
    assert!((r.elapsed - 2.0).abs() < 1e-6, "{}", r.elapsed);
    assert_eq!(r.poses, all, "play_to_time");
    assert_eq!(
        r.poses.iter().filter(|&&t| t as f64 <= 2e6).count(),
        up_to(2.0)
    );

    // Play-one replaces the running play-to: exactly one more entry, then nothing until the
    // outside play-to; no pose is lost or repeated.
    let r = control_in_callback("play_one");
    assert!(r.elapsed < 1.0, "{}", r.elapsed);
    assert_eq!(r.poses, all, "play_one");

    // A jump from the callback: nothing delivered between the 10th pose and 2 s.
    let r = control_in_callback("jump_to_time");
    assert!((r.elapsed - 2.0).abs() < 1e-6, "{}", r.elapsed);
    assert_eq!(&r.poses[..10], &all[..10]);
    assert!(r.poses[10] as f64 > 2e6, "{:?}", &r.poses[..12]);
    assert_eq!(r.poses.len(), 10 + (all.len() - up_to(2.0)), "jump_to_time");
    assert!(sorted(&r.poses));
}

/// Controls called from a callback that `mainloop()` runs (at a rate, not paused) are just as
/// safe, and what they play is delivered by that same pass.
#[test]
fn a_reset_inside_a_mainloop_callback_replays_from_the_start() {
    let conn = Connection::replay_file(&fixture("tracker_udp_lob.out.vrpn")).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    conn.replay().unwrap().set_rate(f64::INFINITY);
    let n = Rc::new(Cell::new(0u32));
    let (c, weak) = (n.clone(), conn.downgrade());
    tracker.on_pose(move |_| {
        c.set(c.get() + 1);
        if c.get() == 100 {
            weak.upgrade().unwrap().replay().unwrap().reset();
        }
    });
    let start = Instant::now();
    while !conn.replay().unwrap().eof() {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "stalled at {}",
            n.get()
        );
        tracker.mainloop().unwrap();
    }
    assert_eq!(n.get(), 100 + 410);
}

/// Issue 29, item 10: a log of a client that reconnected 3,000 times (each session ends in a
/// DISCONNECT entry and the next one describes the same names again) replays every pose. The
/// same names described again after a DISCONNECT are not new names for the per-peer limit
/// (`Limits::max_names_per_peer`, 2,000): replay used to stop after 1,999 sessions.
#[test]
fn a_log_of_many_sessions_replays_every_pose() {
    use vrpn::log::LogWriter;
    use vrpn::wire::payload::tracker::{PosQuat, POS_QUAT};
    use vrpn::wire::{system, Cookie};
    fn description(name: &str) -> Vec<u8> {
        let mut p = ((name.len() + 1) as u32).to_be_bytes().to_vec();
        p.extend_from_slice(name.as_bytes());
        p.push(0);
        p
    }
    const SESSIONS: usize = 3000;
    let path = tmp("many_sessions.vrpn");
    let _ = std::fs::remove_file(&path);
    let mut w = LogWriter::create(&path, &Cookie::ours(0).to_bytes()).unwrap();
    let start = vrpn::TimeVal {
        sec: 1_700_000_000,
        usec: 0,
    };
    let mut pose = [0u8; PosQuat::LEN];
    for i in 0..SESSIONS {
        let t = start.plus(Duration::from_millis(i as u64));
        // Ids as a C++ writer would give them: the sender at 0, the pose type at 3.
        w.log_message(system::SENDER_DESCRIPTION, 0, t, &description("Tracker0"))
            .unwrap();
        w.log_message(system::TYPE_DESCRIPTION, 3, t, &description(POS_QUAT))
            .unwrap();
        PosQuat::new(0, [i as f64, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]).encode(&mut pose);
        w.log_message(3, 0, t, &pose).unwrap();
        w.log_message(system::DISCONNECT, 0, t, &[]).unwrap();
    }
    w.finish().unwrap();

    let conn = Connection::replay_file(&path).unwrap();
    let notices = Rc::new(RefCell::new(Vec::new()));
    let n = notices.clone();
    conn.on_notice(move |notice| n.borrow_mut().push(notice.to_string()));
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let xs = Rc::new(RefCell::new(Vec::new()));
    let x = xs.clone();
    tracker.on_pose(move |p| x.borrow_mut().push(p.pos.x as usize));
    let r = conn.replay().unwrap();
    r.set_rate(0.0);
    r.play_to_time(f64::INFINITY);
    let first: Vec<String> = notices.borrow().iter().take(2).cloned().collect();
    assert!(r.eof(), "not at the end; notices {first:?}");
    let xs = xs.borrow();
    assert_eq!(xs.len(), SESSIONS, "poses replayed; notices {first:?}");
    assert!(xs.iter().copied().eq(0..SESSIONS), "out of order");
    let _ = std::fs::remove_file(&path);
}
