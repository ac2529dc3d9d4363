//! The trackers' reports decoded against the C++ formulas; the Hydra's calibration and mode
//! switch; each keyword (and the HDK's tracker) end to end through a real socket.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use super::hydra::{gamepad_mode_report, motion_mode_report, Wands};
use super::sim::{self, WandRaw};
use super::{decode_spacepoint, decode_wintracker, wintracker_commands, SPACEPOINT, WINTRACKER};
use crate::drivers::hid_quat::normalize;
use crate::hid::fake::HostRequest;
use crate::hid::rig::Rig;
use crate::{TrackerPose, TrackerRemote};

#[test]
fn spacepoint_quaternion_and_buttons() {
    let (q, b) = decode_spacepoint(&sim::spacepoint([32768, 0, 65535, 49152], 3)).unwrap();
    assert_eq!(q, [0.0, -1.0, 32767.0 / 32768.0, 0.5]);
    assert_eq!(b, [true, true]);
    assert!(decode_spacepoint(&[0; 14]).is_none());
}

#[test]
fn wintracker_records_and_commands() {
    let (s, p, q) = decode_wintracker(&sim::wintracker(
        b'2',
        [10000, -5000, 1],
        [10000, 0, 0, -10000],
    ))
    .unwrap();
    assert_eq!(s, Some(2));
    assert_eq!(p, [1.0, -0.5, 0.0001]);
    assert_eq!(q, [0.0, 0.0, -1.0, 1.0]);
    assert_eq!(
        decode_wintracker(&sim::wintracker(b'x', [0; 3], [0; 4]))
            .unwrap()
            .0,
        None
    );
    assert_eq!(
        wintracker_commands(*b"101", b'1', b'Z'),
        vec![
            vec![0, b'S', b'A', b'1', b'0', b'1', b'\n'],
            vec![0, b'S', b'H', b'U', b'\n'],
            vec![0, b'S', b'L', b'\n']
        ]
    );
    assert_eq!(wintracker_commands(*b"111", b'0', b'X').len(), 1);
}

#[test]
fn hydra_decodes_and_calibrates_as_cpp() {
    let mut w = Wands::default();
    // Undocked, never calibrated: raw pose (y and z of the quaternion negated, normalised).
    let raw = WandRaw {
        pos: [-200, 150, -300],
        quat_wxyz: [16384, 16384, 16384, -16384],
        buttons: 0x21,
        stick: [16384, -32768],
        trigger: 255,
    };
    let r = sim::hydra([raw, WandRaw::default()]);
    let a = w.decode(0, &r[8..]);
    assert_eq!(a.pos, [-200.0 * 0.001, 150.0 * 0.001, -300.0 * 0.001]);
    assert_eq!(a.quat, normalize(&[0.5, -0.5, 0.5, 0.5]));
    assert_eq!(a.buttons, [true, false, false, false, false, true, false]);
    assert_eq!(a.analog, [0.5, -1.0, 255.0 * (1.0 / 255.0)]);
    // Docked (|pos| < 0.1 m) left of the base, below: the reference orientation; the pose
    // becomes the identity and x keeps its sign.
    let dock = WandRaw {
        pos: [-50, -20, -10],
        quat_wxyz: [16384, 16384, 16384, -16384],
        ..WandRaw::default()
    };
    let d = w.decode(0, &sim::hydra([dock, WandRaw::default()])[8..]);
    let i = d.quat;
    assert!((i[3] - 1.0).abs() < 1e-12 && i[0].abs() < 1e-12, "{i:?}");
    assert_eq!(d.pos, [-0.05, -0.02, -0.01]);
    // Docked above the base: the hemisphere flips (mirror −1), and x's sign follows.
    let mut w2 = Wands::default();
    let up = WandRaw {
        pos: [30, 40, 0],
        quat_wxyz: [32767, 0, 0, 0],
        ..WandRaw::default()
    };
    let u = w2.decode(1, &sim::hydra([WandRaw::default(), up])[30..]);
    // Mirror −1 (y > 0); the right wand wants x > 0 after mirroring, −0.03 is not: sign −1;
    // then x × sign × mirror = 0.03, y × mirror = −0.04.
    assert_eq!(u.pos, [0.03, -0.04, 0.0]);
}

#[test]
fn hydra_mode_reports_are_the_cpp_bytes() {
    let m = motion_mode_report();
    let g = gamepad_mode_report();
    assert_eq!(m.len(), 91);
    assert_eq!((m[6], m[8], m[9], m[89]), (1, 4, 3, 6));
    assert_eq!((g[6], g[8], g[9], g[89]), (1, 4, 0, 5));
    assert_eq!(m.iter().filter(|b| **b != 0).count(), 4);
}

fn q4(q: &nalgebra::UnitQuaternion<f64>) -> [f64; 4] {
    [q.i, q.j, q.k, q.w]
}

fn p3(p: &TrackerPose) -> [f64; 3] {
    [p.pos.x, p.pos.y, p.pos.z]
}

fn poses(rig: &Rig, name: &str) -> (TrackerRemote, Rc<RefCell<Vec<TrackerPose>>>) {
    let tr = TrackerRemote::on_connection(name, &rig.client).unwrap();
    let got: Rc<RefCell<Vec<TrackerPose>>> = Rc::default();
    let g = got.clone();
    tr.on_pose(move |p| g.borrow_mut().push(*p));
    (tr, got)
}

#[test]
fn spacepoint_and_wintracker_end_to_end() {
    let mut rig = Rig::new();
    rig.connect();
    // Two SpacePoints; the line with index 1 takes the second.
    rig.devices
        .push(super::build_spacepoint("Sp1", 1, &rig.server, &rig.hub).unwrap());
    rig.devices
        .push(super::build_spacepoint("Sp0", 0, &rig.server, &rig.hub).unwrap());
    rig.devices
        .push(super::build_wintracker("Win", *b"110", b'0', b'Z', &rig.server, &rig.hub).unwrap());
    let (_t0, p0) = poses(&rig, "Sp0");
    let (_t1, p1) = poses(&rig, "Sp1");
    let (_tw, pw) = poses(&rig, "Win");
    let b0 = crate::ButtonRemote::on_connection("Sp0", &rig.client).unwrap();
    let pressed = Rc::new(RefCell::new(Vec::new()));
    let pr = pressed.clone();
    b0.on_change(move |c| pr.borrow_mut().push((c.button, c.state.raw())));
    let l0 = rig.plug(5, SPACEPOINT.0, SPACEPOINT.1, 1, "SpacePoint");
    let l1 = rig.plug(6, SPACEPOINT.0, SPACEPOINT.1, 1, "SpacePoint");
    let e0 = rig.accept(&l0);
    let e1 = rig.accept(&l1);
    e0.send_report(&sim::spacepoint([32768, 32768, 32768, 65535], 2))
        .unwrap();
    e1.send_report(&sim::spacepoint([0, 32768, 32768, 32768], 0))
        .unwrap();
    rig.until("both SpacePoints", |_| {
        !p0.borrow().is_empty() && !p1.borrow().is_empty()
    });
    assert_eq!(q4(&p0.borrow()[0].quat), [0.0, 0.0, 0.0, 32767.0 / 32768.0]);
    assert_eq!(q4(&p1.borrow()[0].quat), [-1.0, 0.0, 0.0, 0.0]);
    rig.until("SpacePoint button", |_| *pressed.borrow() == vec![(1, 1)]);
    // The WinTracker is sent its commands at open, then streams.
    let lw = rig.plug(7, WINTRACKER.0, WINTRACKER.1, 0, "WinTracker");
    let ew = rig.accept(&lw);
    let mut cmds = Vec::new();
    rig.until("WinTracker commands", |_| {
        while let Ok(Some(HostRequest::Output(c))) = ew.try_request() {
            cmds.push(c);
        }
        cmds.len() == 2
    });
    assert_eq!(cmds, wintracker_commands(*b"110", b'0', b'Z'));
    ew.send_report(&sim::wintracker(
        b'1',
        [1000, 2000, -3000],
        [10000, 0, 0, 0],
    ))
    .unwrap();
    rig.until("WinTracker pose", |_| !pw.borrow().is_empty());
    let p = pw.borrow()[0];
    assert_eq!(p.sensor, 1);
    assert_eq!(p3(&p), [0.1, 0.2, -0.3]);
    assert_eq!(q4(&p.quat), [0.0, 0.0, 0.0, 1.0]);
}

#[test]
fn hdk_end_to_end() {
    use crate::drivers::hmd::{hdk, sim as hsim};
    let mut rig = Rig::new();
    rig.connect();
    rig.devices
        .push(hdk::build("Hdk", &rig.server, &rig.hub).unwrap());
    let tr = TrackerRemote::on_connection("Hdk", &rig.client).unwrap();
    let got: Rc<RefCell<Vec<TrackerPose>>> = Rc::default();
    let vel = Rc::new(RefCell::new(Vec::new()));
    let (g, v) = (got.clone(), vel.clone());
    tr.on_pose(move |p| g.borrow_mut().push(*p));
    tr.on_velocity(move |x| v.borrow_mut().push(q4(&x.vel_quat)));
    let ar = crate::AnalogRemote::on_connection("Hdk", &rig.client).unwrap();
    let ch = Rc::new(RefCell::new(Vec::new()));
    let c = ch.clone();
    ar.on_report(move |r| c.borrow_mut().push(r.channels().to_vec()));
    let l = rig.plug(9, hdk::IDS[1].0, hdk::IDS[1].1, 0, "HDK");
    let e = rig.accept(&l);
    let report = hsim::hdk(0x13, 1, [0, 0, 8192, 14189], [0, 0, 512], 32);
    e.send_report(&report).unwrap();
    let want = hdk::decode(&report).unwrap();
    rig.until("HDK pose, velocity, status", |_| {
        !got.borrow().is_empty() && !vel.borrow().is_empty() && !ch.borrow().is_empty()
    });
    assert_eq!(q4(&got.borrow()[0].quat), want.quat);
    assert_eq!(vel.borrow()[0], want.vel_quat.unwrap());
    assert_eq!(ch.borrow()[0], vec![3.0, hdk::STATUS_LANDSCAPE]);
    // Unplugged: version and status go back to 0.
    drop(e);
    rig.unplug(9);
    rig.until("status unknown", |_| {
        ch.borrow().last() == Some(&vec![0.0, 0.0])
    });
}

#[test]
fn hydra_switches_modes_then_streams() {
    use std::sync::mpsc;
    let mut rig = Rig::new();
    rig.connect();
    rig.devices
        .push(super::hydra::build("Hydra", &rig.server, &rig.hub).unwrap());
    let texts = Rc::new(RefCell::new(Vec::<String>::new()));
    let t = texts.clone();
    let sender = rig.client.register_sender("Hydra").unwrap();
    let ty = rig
        .client
        .register_type(crate::devices::base::TEXT_MESSAGE)
        .unwrap();
    rig.client
        .register_handler(ty, crate::SenderFilter::Only(sender), move |m| {
            if let Some((_, _, s)) = crate::devices::text::decode_text(m.payload) {
                t.borrow_mut().push(s.to_owned());
            }
        });
    let (tr, got) = poses(&rig, "Hydra");
    // The control interface answers feature requests from its own thread (the host waits
    // for the answer, as the ioctl does).
    let data = rig.plug(
        30,
        super::hydra::IDS.0,
        super::hydra::IDS.1,
        0,
        "Razer Hydra",
    );
    rig.fake.add_hidraw(
        31,
        super::hydra::IDS.0,
        super::hydra::IDS.1,
        1,
        "Razer Hydra",
        "",
    );
    let control = rig.fake.listen_hidraw(31).unwrap();
    let (tx, rx) = mpsc::channel();
    let sim = std::thread::spawn(move || {
        let end = loop {
            if let Some(e) = control.accept().unwrap() {
                break e;
            }
            std::thread::sleep(Duration::from_millis(1));
        };
        loop {
            match end.try_request() {
                Ok(Some(HostRequest::GetFeature { len, .. })) => {
                    end.answer_feature(&sim::hydra_feature("HYD12345678901234", len.into()))
                        .unwrap();
                }
                Ok(Some(HostRequest::SetFeature(f))) => tx.send(f).unwrap(),
                Ok(_) => std::thread::sleep(Duration::from_millis(1)),
                Err(_) => return,
            }
        }
    });
    rig.fake.uevent("add", "hidraw", "hidraw31").unwrap();
    let end = rig.accept(&data);
    rig.until("serial number", |_| {
        texts
            .borrow()
            .iter()
            .any(|t| t == "Connected to Razer Hydra with serial number HYD12345678901234")
    });
    // No report within 1 s: the mode switch.
    let mut switched = None;
    rig.until("mode switch", |_| {
        switched = rx.try_recv().ok();
        switched.is_some()
    });
    assert_eq!(switched.unwrap(), motion_mode_report().to_vec());
    let raw = WandRaw {
        pos: [-200, 150, -300],
        quat_wxyz: [32767, 0, 0, 0],
        buttons: 0x04,
        stick: [0, 0],
        trigger: 0,
    };
    end.send_report(&sim::hydra([raw, raw])).unwrap();
    rig.until("two poses", |_| got.borrow().len() == 2);
    let want = Wands::default().decode(0, &sim::hydra([raw, raw])[8..]);
    assert_eq!(p3(&got.borrow()[0]), want.pos);
    assert_eq!(got.borrow()[1].sensor, 1);
    assert!(texts
        .borrow()
        .iter()
        .any(|t| t.starts_with("Got first motion controller report!")));
    // The server stops: back to gamepad mode.
    rig.devices.clear();
    let back = rx.recv_timeout(Duration::from_secs(5)).unwrap();
    assert_eq!(back, gamepad_mode_report().to_vec());
    drop(end);
    drop(tr);
    sim.join().unwrap();
}
