//! Layered trackers (AnalogFly and ButtonFly): scripted analog and button input through sources on
//! the same connection, with a pinned clock, against poses worked out by hand; several flyers
//! over one joystick; and `vrpn.cfg` entries built by `build_devices`, including a source on
//! another server.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::layered::config::{AnalogFly, ButtonFly};
use vrpn::server::build_devices;
use vrpn::server::config::{parse_one, parse_str};
use vrpn::{
    AnalogRemote, AnalogServer, ButtonServer, Connection, TimeVal, TrackerAnalogFly,
    TrackerButtonFly, TrackerRemote,
};

const H: f64 = std::f64::consts::FRAC_1_SQRT_2;
const EPS: f64 = 1e-12;

/// A pose as a client saw it: (time, pos, quat xyzw).
type Seen = (TimeVal, [f64; 3], [f64; 4]);

fn analog_fly_cfg(text: &str) -> AnalogFly {
    assert_eq!(parse_str(text, "vrpn.cfg").unwrap().len(), 1);
    parse_one(text)
}

fn button_fly_cfg(text: &str) -> ButtonFly {
    assert_eq!(parse_str(text, "vrpn.cfg").unwrap().len(), 1);
    parse_one(text)
}

/// A client of `name` on `conn` recording every pose.
fn watch(name: &str, conn: &Connection) -> (TrackerRemote, Rc<RefCell<Vec<Seen>>>) {
    let remote = TrackerRemote::on_connection(name, conn).unwrap();
    let seen = Rc::new(RefCell::new(Vec::new()));
    let s = seen.clone();
    remote.on_pose(move |p| {
        assert_eq!(p.sensor, 0);
        s.borrow_mut().push((
            p.time,
            [p.pos.x, p.pos.y, p.pos.z],
            [p.quat.i, p.quat.j, p.quat.k, p.quat.w],
        ))
    });
    (remote, seen)
}

fn assert_pose(got: &Seen, pos: [f64; 3], quat: [f64; 4]) {
    let ok = (0..3).all(|i| (got.1[i] - pos[i]).abs() < EPS)
        && (0..4).all(|i| (got.2[i] - quat[i]).abs() < EPS);
    assert!(
        ok,
        "got pos {:?} quat {:?}, expected {pos:?} {quat:?}",
        got.1, got.2
    );
}

const T0: TimeVal = TimeVal {
    sec: 1_000,
    usec: 0,
};

/// `T0` plus `us` microseconds.
fn t(us: i64) -> TimeVal {
    TimeVal::from_micros(T0.as_micros() + us)
}

/// Sends channel values from `joy` stamped `time` and lets the connection deliver them.
fn send(conn: &Connection, joy: &mut AnalogServer, values: &[f64], time: TimeVal) {
    joy.channels_mut()[..values.len()].copy_from_slice(values);
    joy.report(Some(time)).unwrap();
    conn.mainloop().unwrap();
}

/// One pass of `fly` at clock `now`, then delivery of what it sent.
fn step(conn: &Connection, fly: &mut TrackerAnalogFly, now: TimeVal) {
    fly.set_clock(Some(now));
    fly.poll();
    conn.mainloop().unwrap();
}

const IDENT: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

#[test]
fn absolute_mode_threshold_power_scale() {
    let conn = Connection::new_loopback();
    let mut joy = AnalogServer::new("Joy", &conn, 6).unwrap();
    // Rate 8 Hz: interval = 1/8 = 0.125 s exactly.
    let mut fly = TrackerAnalogFly::new(
        &analog_fly_cfg(
            "vrpn_Tracker_AnalogFly Fly 8 absolute\n\
             X *Joy 0 0.0 0.0 1.0 1.0\n\
             Y *Joy 1 0.5 0.1 2.0 1.0\n\
             Z *Joy 2 0.0 0.0 1.0 2.0\n\
             RZ *Joy 5 0.0 0.0 0.25 1.0\n\n",
        ),
        &conn,
    )
    .unwrap();
    let (_client, seen) = watch("Fly", &conn);
    fly.set_clock(Some(T0));
    fly.reset();

    let msg_time = TimeVal::new(77, 5);
    send(&conn, &mut joy, &[0.3, 0.55, -0.5, 0.0, 0.0, 1.0], msg_time);
    // Not due yet: 0.1 s < 0.125 s.
    step(&conn, &mut fly, t(100_000));
    assert!(seen.borrow().is_empty());
    step(&conn, &mut fly, t(125_000));
    assert_eq!(seen.borrow().len(), 1);
    // X: 0.3 − 0 = 0.3 > 0 → (0.3·1)^1 = 0.3.
    // Y: 0.55 − 0.5 = 0.05 ≤ threshold 0.1 → 0.
    // Z: −0.5 − 0 < 0 → −(|−0.5|·1)^2 = −0.25.
    // RZ: (1.0·0.25)^1 = 0.25 rev → rz = 0.25·1·2π = π/2; D = EulerCol(yaw π/2) has rows
    //   (0,−1,0), (1,0,0), (0,0,1); QuatFromRowMatrix: tr = 1 > 0, s = √2, w = √2/2,
    //   z = (M01 − M10)·0.5/√2 = (−1 − 1)/(2√2) = −√½, x = y = 0.
    // Absolute: report time = time of the last channel message.
    {
        let s = seen.borrow();
        assert_eq!(s[0].0, msg_time);
        assert_pose(&s[0], [0.3, 0.0, -0.25], [0.0, 0.0, -H, H]);
    }

    // Y below the offset: o = 0.2 − 0.5 = −0.3, |o| > 0.1 → −(0.3·2)^1 = −0.6; RZ back to 0.
    let msg_time = TimeVal::new(78, 0);
    send(&conn, &mut joy, &[0.3, 0.2, -0.5, 0.0, 0.0, 0.0], msg_time);
    step(&conn, &mut fly, t(250_000));
    let s = seen.borrow();
    assert_eq!(s.len(), 2);
    assert_eq!(s[1].0, msg_time);
    assert_pose(&s[1], [0.3, -0.6, -0.25], IDENT);
    // The processed values themselves.
    let v = fly.values();
    assert!((v[0] - 0.3).abs() < EPS && (v[1] + 0.6).abs() < EPS && (v[2] + 0.25).abs() < EPS);
    assert_eq!((v[3], v[4], v[5]), (0.0, 0.0, 0.0));
}

fn differential(world: bool) -> Vec<Seen> {
    let conn = Connection::new_loopback();
    let mut joy = AnalogServer::new("Joy", &conn, 6).unwrap();
    let text = format!(
        "vrpn_Tracker_AnalogFly Fly 8 differential\n\
         X *Joy 0 0.0 0.0 1.0 1.0\n\
         RZ *Joy 5 0.0 0.0 2.0 1.0\n\
         {}\n",
        if world { "WORLDFRAME\n" } else { "" }
    );
    let mut fly = TrackerAnalogFly::new(&analog_fly_cfg(&text), &conn).unwrap();
    let (_client, seen) = watch("Fly", &conn);
    fly.set_clock(Some(T0));
    fly.reset();
    let any = TimeVal::new(1, 0);
    // Step 1: X = 2 m/s for dt = 0.125 s → +0.25 m along x.
    send(&conn, &mut joy, &[2.0, 0.0, 0.0, 0.0, 0.0, 0.0], any);
    step(&conn, &mut fly, t(125_000));
    // Step 2: RZ = 1.0·2.0 = 2 rev/s for 0.125 s → rz = 2·0.125·2π = π/2 (a −90° turn about z).
    send(&conn, &mut joy, &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0], any);
    step(&conn, &mut fly, t(250_000));
    // Step 3: X = 2 m/s again, no rotation.
    send(&conn, &mut joy, &[2.0, 0.0, 0.0, 0.0, 0.0, 0.0], any);
    step(&conn, &mut fly, t(375_000));
    let s = seen.borrow().clone();
    s
}

#[test]
fn differential_local_frame() {
    let s = differential(false);
    assert_eq!(s.len(), 3);
    // Differential: report time = the clock at the report.
    assert_eq!(
        (s[0].0, s[1].0, s[2].0),
        (t(125_000), t(250_000), t(375_000))
    );
    assert_pose(&s[0], [0.25, 0.0, 0.0], IDENT);
    // D has no translation: row 3 of D × Current = row 3 of Current; rotation as in the absolute
    // test: (0, 0, −√½, √½).
    assert_pose(&s[1], [0.25, 0.0, 0.0], [0.0, 0.0, -H, H]);
    // Local frame: row 3 = 0.25·Current[0] + Current[3] = 0.25·(0,−1,0) + (0.25,0,0)
    // (Current[0] = (cos π/2, −sin π/2, 0)): the step goes along the turned x axis.
    assert_pose(&s[2], [0.25, -0.25, 0.0], [0.0, 0.0, -H, H]);
}

#[test]
fn differential_world_frame() {
    let s = differential(true);
    assert_eq!(s.len(), 3);
    assert_pose(&s[0], [0.25, 0.0, 0.0], IDENT);
    assert_pose(&s[1], [0.25, 0.0, 0.0], [0.0, 0.0, -H, H]);
    // World frame: the translation is added unrotated: (0.25,0,0) + (0.25,0,0).
    assert_pose(&s[2], [0.5, 0.0, 0.0], [0.0, 0.0, -H, H]);
}

#[test]
fn differential_interval_gates_and_integrates_measured_dt() {
    let conn = Connection::new_loopback();
    let mut joy = AnalogServer::new("Joy", &conn, 1).unwrap();
    let mut fly = TrackerAnalogFly::new(
        &analog_fly_cfg("vrpn_Tracker_AnalogFly Fly 8 differential\nX *Joy 0 0 0 1 1\n\n"),
        &conn,
    )
    .unwrap();
    let (_client, seen) = watch("Fly", &conn);
    fly.set_clock(Some(T0));
    fly.reset();
    send(&conn, &mut joy, &[1.0], TimeVal::new(1, 0));
    step(&conn, &mut fly, t(124_999)); // 0.124999 s < 0.125: nothing
    assert!(seen.borrow().is_empty());
    // A late pass integrates the whole measured interval: 1 m/s · 0.3 s = 0.3 m.
    step(&conn, &mut fly, t(300_000));
    // Then 1 m/s · 0.2 s more = 0.5 m.
    step(&conn, &mut fly, t(500_000));
    let s = seen.borrow();
    assert_eq!(s.len(), 2);
    assert_pose(&s[0], [0.3, 0.0, 0.0], IDENT);
    assert_pose(&s[1], [0.5, 0.0, 0.0], IDENT);
}

#[test]
fn reset_button_returns_to_identity() {
    let conn = Connection::new_loopback();
    let mut joy = AnalogServer::new("Joy", &conn, 1).unwrap();
    let btn = ButtonServer::new("Btn", &conn, 2).unwrap();
    let mut fly = TrackerAnalogFly::new(
        &analog_fly_cfg(
            "vrpn_Tracker_AnalogFly Fly 8 differential\nX *Joy 0 0 0 1 1\nRESET *Btn 0\n\n",
        ),
        &conn,
    )
    .unwrap();
    let (_client, seen) = watch("Fly", &conn);
    fly.set_clock(Some(T0));
    fly.reset();
    send(&conn, &mut joy, &[2.0], TimeVal::new(1, 0));
    // 2 · 0.125 = 0.25, then 0.25 + 0.25 = 0.5
    step(&conn, &mut fly, t(125_000));
    step(&conn, &mut fly, t(250_000));
    // Button 1 is not the reset button.
    btn.set_button(1, true);
    btn.report_changes().unwrap();
    conn.mainloop().unwrap();
    // 0.5 + 0.25 = 0.75
    step(&conn, &mut fly, t(375_000));
    // Press the reset button at 0.4 s: pose identity, interval restarts at 0.4 s.
    fly.set_clock(Some(t(400_000)));
    btn.set_button(0, true);
    btn.report_changes().unwrap();
    conn.mainloop().unwrap();
    assert_eq!(fly.pose(), ([0.0; 3], IDENT));
    step(&conn, &mut fly, t(500_000)); // 0.1 s since the reset: not due
    step(&conn, &mut fly, t(525_000)); // 2 · 0.125 = 0.25 from identity
    let s = seen.borrow();
    assert_eq!(s.len(), 4);
    assert_pose(&s[0], [0.25, 0.0, 0.0], IDENT);
    assert_pose(&s[1], [0.5, 0.0, 0.0], IDENT);
    assert_pose(&s[2], [0.75, 0.0, 0.0], IDENT);
    assert_pose(&s[3], [0.25, 0.0, 0.0], IDENT);
    assert_eq!(s[3].0, t(525_000));
}

#[test]
fn clutch_freezes_and_resumes_absolute() {
    let conn = Connection::new_loopback();
    let mut joy = AnalogServer::new("Joy", &conn, 1).unwrap();
    let btn = ButtonServer::new("Btn", &conn, 2).unwrap();
    let mut fly = TrackerAnalogFly::new(
        &analog_fly_cfg(
            "vrpn_Tracker_AnalogFly Fly 8 absolute\nX *Joy 0 0 0 1 1\nCLUTCH *Btn 1\n\n",
        ),
        &conn,
    )
    .unwrap();
    let (_client, seen) = watch("Fly", &conn);
    fly.set_clock(Some(T0));
    fly.reset();
    let clutch = |on: bool| {
        btn.set_button(1, on);
        btn.report_changes().unwrap();
        conn.mainloop().unwrap();
    };
    let any = TimeVal::new(1, 0);
    // 1: clutch not held (a configured clutch starts released): frozen at identity, still sent.
    send(&conn, &mut joy, &[0.3], any);
    step(&conn, &mut fly, t(125_000));
    // 2: clutch engaged. Re-engagement: D = I with row 3 (0.3,0,0); its inverse has row 3
    // (−0.3,0,0); Clutch = Dinv × Current(I) = Dinv. Current = D × Clutch: row 3 =
    // 0.3·Clutch[0] + Clutch[3] = (0.3,0,0) + (−0.3,0,0) = 0 → continues from the frozen pose.
    clutch(true);
    step(&conn, &mut fly, t(250_000));
    // 3: X = 0.5: row 3 = (0.5,0,0) + (−0.3,0,0) = (0.2,0,0).
    send(&conn, &mut joy, &[0.5], any);
    step(&conn, &mut fly, t(375_000));
    // 4: released, X = 1.0: frozen at (0.2,0,0).
    clutch(false);
    send(&conn, &mut joy, &[1.0], any);
    step(&conn, &mut fly, t(500_000));
    // 5: engaged again: Clutch = Dinv(row 3 (−1,0,0)) × Current(row 3 (0.2,0,0)) → row 3
    // (−0.8,0,0); Current = D × Clutch → (1.0 − 0.8) = 0.2: no jump.
    clutch(true);
    step(&conn, &mut fly, t(625_000));
    // 6: X = 1.5 → 1.5 − 0.8 = 0.7.
    send(&conn, &mut joy, &[1.5], any);
    step(&conn, &mut fly, t(750_000));
    let s = seen.borrow();
    assert_eq!(s.len(), 6);
    let xs = [0.0, 0.0, 0.2, 0.2, 0.2, 0.7];
    for (got, x) in s.iter().zip(xs) {
        assert_pose(got, [x, 0.0, 0.0], IDENT);
    }
}

#[test]
fn clutch_differential_moves_only_while_held() {
    let conn = Connection::new_loopback();
    let mut joy = AnalogServer::new("Joy", &conn, 1).unwrap();
    let btn = ButtonServer::new("Btn", &conn, 1).unwrap();
    let mut fly = TrackerAnalogFly::new(
        &analog_fly_cfg(
            "vrpn_Tracker_AnalogFly Fly 8 differential\nX *Joy 0 0 0 1 1\nCLUTCH *Btn 0\n\n",
        ),
        &conn,
    )
    .unwrap();
    let (_client, seen) = watch("Fly", &conn);
    fly.set_clock(Some(T0));
    fly.reset();
    send(&conn, &mut joy, &[2.0], TimeVal::new(1, 0));
    let clutch = |on: bool| {
        btn.set_button(0, on);
        btn.report_changes().unwrap();
        conn.mainloop().unwrap();
    };
    step(&conn, &mut fly, t(125_000)); // released: 0
    clutch(true);
    step(&conn, &mut fly, t(250_000)); // 2 · 0.125 = 0.25
    clutch(false);
    step(&conn, &mut fly, t(375_000)); // frozen 0.25
    clutch(true);
    step(&conn, &mut fly, t(500_000)); // 0.5
    let s = seen.borrow();
    let xs = [0.0, 0.25, 0.25, 0.5];
    assert_eq!(s.len(), 4);
    for (got, x) in s.iter().zip(xs) {
        assert_pose(got, [x, 0.0, 0.0], IDENT);
    }
}

#[test]
fn two_flyers_over_one_joystick_and_a_direct_client() {
    let conn = Connection::new_loopback();
    let mut joy = AnalogServer::new("Joy", &conn, 2).unwrap();
    let mut a = TrackerAnalogFly::new(
        &analog_fly_cfg("vrpn_Tracker_AnalogFly FlyA 8 absolute\nX *Joy 0 0 0 1 1\n\n"),
        &conn,
    )
    .unwrap();
    let mut b = TrackerAnalogFly::new(
        &analog_fly_cfg(
            "vrpn_Tracker_AnalogFly FlyB 8 absolute\nX *Joy 0 0 0 -2 1\nY *Joy 1 0 0 1 2\n\n",
        ),
        &conn,
    )
    .unwrap();
    let (_ca, seen_a) = watch("FlyA", &conn);
    let (_cb, seen_b) = watch("FlyB", &conn);
    let direct = AnalogRemote::on_connection("Joy", &conn).unwrap();
    a.set_clock(Some(T0));
    a.reset();
    b.set_clock(Some(T0));
    b.reset();
    send(&conn, &mut joy, &[0.4, -3.0], TimeVal::new(5, 0));
    step(&conn, &mut a, t(125_000));
    step(&conn, &mut b, t(125_000));
    // FlyA: x = 0.4. FlyB: x = (0.4·−2)^1 = −0.8 (integer power: a negative scale inverts);
    // y = −(|−3|·1)^2 = −9.
    assert_pose(&seen_a.borrow()[0], [0.4, 0.0, 0.0], IDENT);
    assert_pose(&seen_b.borrow()[0], [-0.8, -9.0, 0.0], IDENT);
    assert_eq!(direct.channel(0), 0.4);
    assert_eq!(direct.channel(1), -3.0);
}

#[test]
fn button_fly_jumps_and_flies() {
    let conn = Connection::new_loopback();
    let btn = ButtonServer::new("Btn", &conn, 3).unwrap();
    let mut joy = AnalogServer::new("Joy", &conn, 1).unwrap();
    let mut fly = TrackerButtonFly::new(
        &button_fly_cfg(
            "vrpn_Tracker_ButtonFly BFly 8\n\
             absolute *Btn 0 1.0 2.0 3.0 0.0 0.0 0.25\n\
             differential *Btn 1 0.0 0.0 -1.0 0.0 0.0 0.0\n\
             differential *Btn 2 0.0 0.0 0.0 0.0 0.0 2.0\n\
             vel_scale *Joy 0 0.0 2.0 1.0\n\
             end\n",
        ),
        &conn,
    )
    .unwrap();
    let (_client, seen) = watch("BFly", &conn);
    let press = |i: usize, on: bool| {
        btn.set_button(i, on);
        btn.report_changes().unwrap();
        conn.mainloop().unwrap();
    };
    let step = |fly: &mut TrackerButtonFly, now: TimeVal| {
        fly.set_clock(Some(now));
        fly.poll();
        conn.mainloop().unwrap();
    };
    fly.set_clock(Some(T0));
    fly.reset();

    // Absolute press: Current = EulerCol(yaw 0.25·2π = π/2) with row 3 (1,2,3): pos (1,2,3),
    // quat (0,0,−√½,√½) as in the AnalogFly tests. Reported on the next pass even though the
    // interval (0.01 s) is not due; no differential axis is held so update() changes nothing.
    press(0, true);
    step(&mut fly, t(10_000));
    press(0, false); // releases are ignored
    step(&mut fly, t(20_000)); // 0.01 s since the report: nothing
    assert_eq!(seen.borrow().len(), 1);
    assert_eq!(seen.borrow()[0].0, t(10_000));
    assert_pose(&seen.borrow()[0], [1.0, 2.0, 3.0], [0.0, 0.0, -H, H]);

    // vel_scale: o = 0.75 − 0 ≥ 0, f = |0.75·2|^1 = 1.5.
    joy.channels_mut()[0] = 0.75;
    joy.report(None).unwrap();
    conn.mainloop().unwrap();
    assert_eq!(fly.scales(), (1.5, 1.0));
    // Hold button 1 (z at −1 m/s) for dt = 0.135 − 0.01 = 0.125 s: tz = −1·0.125·1.5 = −0.1875.
    // Row 3 of D × Current = −0.1875·Current[2] + Current[3] = −0.1875·(0,0,1) + (1,2,3)
    // (row 2 of EulerCol(yaw only) is (0,0,1)).
    press(1, true);
    step(&mut fly, t(135_000));
    assert_pose(&seen.borrow()[1], [1.0, 2.0, 2.8125], [0.0, 0.0, -H, H]);
    // Release 1, hold 2 (2 rev/s about z): rz = 2·0.125·2π·1 = π/2; another −90° about z makes
    // −180°: rows (−1,0,0), (0,−1,0), (0,0,1); tr = −1 → largest diagonal is z: s = √(1+1+1+1) =
    // 2, z = 1, w = (M01 − M10)·¼ = 0 → (0,0,1,0). No translation: pos unchanged.
    press(1, false);
    press(2, true);
    step(&mut fly, t(260_000));
    assert_pose(&seen.borrow()[2], [1.0, 2.0, 2.8125], [0.0, 0.0, 1.0, 0.0]);
    assert_eq!(seen.borrow()[2].0, t(260_000));
    // Nothing held: the pose holds and reports continue every interval.
    press(2, false);
    step(&mut fly, t(385_000));
    let s = seen.borrow();
    assert_eq!(s.len(), 4);
    assert_pose(&s[3], [1.0, 2.0, 2.8125], [0.0, 0.0, 1.0, 0.0]);
}

fn pump(
    conns: &[&Connection],
    devices: &mut [Box<dyn vrpn::ServerDevice>],
    mut done: impl FnMut() -> bool,
) {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(10) {
        let now = vrpn::Now::read();
        for d in devices.iter_mut() {
            d.mainloop(now);
        }
        for c in conns {
            c.mainloop().unwrap();
        }
        if done() {
            return;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    panic!("timed out");
}

#[test]
fn config_round_trip_with_local_and_remote_sources() {
    // Server A: the joystick. Server B (built from vrpn.cfg): two flyers on A's joystick over the
    // network, one on B's own buttons, and a ButtonFly.
    let srv_a = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port_a = srv_a.local_port().unwrap();
    let mut joy = AnalogServer::new("Joy", &srv_a, 2).unwrap();
    let srv_b = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port_b = srv_b.local_port().unwrap();
    let btn = ButtonServer::new("Btn", &srv_b, 1).unwrap();
    let cfg = format!(
        "# layered devices\n\
         vrpn_Tracker_AnalogFly FlyA 60 absolute\n\
         X Joy@127.0.0.1:{port_a} 0 0.0 0.0 1.0 1.0\n\
         \n\
         vrpn_Tracker_AnalogFly FlyB 60 absolute\n\
         Y Joy@127.0.0.1:{port_a} 1 0.0 0.0 2.0 1.0\n\
         RESET *Btn 0\n\
         \n\
         vrpn_Tracker_ButtonFly BFly 60\n\
         absolute *Btn 0 0.0 0.0 5.0 0.0 0.0 0.0\n\
         end\n"
    );
    let entries = parse_str(&cfg, "vrpn.cfg").unwrap();
    let mut devices = build_devices(&entries, &srv_b, false, None, |_| {}).unwrap();
    let names: Vec<_> = devices.iter().map(|d| d.name().to_string()).collect();
    assert_eq!(names, ["FlyA", "FlyB", "BFly"]);

    // A client of B watching two layered trackers and the low-level button at the same time.
    let fa = TrackerRemote::new(&format!("FlyA@127.0.0.1:{port_b}")).unwrap();
    let fb = TrackerRemote::new(&format!("FlyB@127.0.0.1:{port_b}")).unwrap();
    let bf = TrackerRemote::new(&format!("BFly@127.0.0.1:{port_b}")).unwrap();
    let br = vrpn::ButtonRemote::new(&format!("Btn@127.0.0.1:{port_b}")).unwrap();
    let client = fa.connection().clone();
    joy.channels_mut().copy_from_slice(&[0.4, -0.25]);
    pump(&[&srv_a, &srv_b, &client], &mut devices, || {
        let _ = joy.report(None);
        // FlyA: x = 0.4; FlyB: y = −(0.25·2) = −0.5.
        fa.pose(0).is_some_and(|p| p.pos.x == 0.4)
            && fb.pose(0).is_some_and(|p| p.pos.y == -0.5)
            && bf.pose(0).is_some()
    });
    // A button press reaches the plain client and BFly jumps to z = 5.
    btn.set_button(0, true);
    btn.report_changes().unwrap();
    pump(&[&srv_a, &srv_b, &client], &mut devices, || {
        br.pressed(0) && bf.pose(0).is_some_and(|p| p.pos.z == 5.0)
    });
}
