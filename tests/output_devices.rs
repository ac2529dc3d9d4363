//! Analog_Output and Poser: client requests reach the server, with the C++ quirks.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::analog_output::{AnalogOutputRemote, AnalogOutputServer};
use vrpn::devices::poser::{q_mult, PoserRemote, PoserServer};
use vrpn::{Connection, TimeVal};

#[test]
fn analog_output_requests_in_process() {
    let conn = Connection::new_loopback();
    let server = AnalogOutputServer::new("Out0", &conn, 3).unwrap();
    let remote = AnalogOutputRemote::on_connection("Out0", &conn).unwrap();
    let seen = Rc::new(RefCell::new(Vec::new()));
    let s = seen.clone();
    server.on_request(move |v| s.borrow_mut().push(v.channels().to_vec()));
    remote.request_change_channel_value(1, 0.75).unwrap();
    conn.mainloop().unwrap();
    assert_eq!(seen.borrow().last().unwrap(), &vec![0.0, 0.75, 0.0]);
    // Out of range: ignored, but the callback still runs (as the C++ callback server).
    remote.request_change_channel_value(7, 9.0).unwrap();
    assert_eq!(seen.borrow().len(), 2);
    assert_eq!(seen.borrow()[1], vec![0.0, 0.75, 0.0]);
    // More values than channels: clamped to the count.
    remote
        .request_change_channels(&[1.0, 2.0, 3.0, 4.0, 5.0])
        .unwrap();
    assert_eq!(server.values().channels(), &[1.0, 2.0, 3.0]);
    assert_eq!(seen.borrow().len(), 3);
    assert_eq!(remote.num_channels(), 128);
    server.report_num_channels().unwrap();
    assert_eq!(remote.num_channels(), 3);
}

#[test]
fn analog_output_announces_channels_on_connection() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = srv.local_port().unwrap();
    let server = AnalogOutputServer::new("Out0", &srv, 5).unwrap();
    let remote = AnalogOutputRemote::new(&format!("Out0@127.0.0.1:{port}")).unwrap();
    let reported = Rc::new(Cell::new(-1));
    let r = reported.clone();
    remote.on_num_channels(move |n| r.set(*n));
    let start = Instant::now();
    let mut sent = false;
    while start.elapsed() < Duration::from_secs(10) {
        srv.mainloop().unwrap();
        remote.mainloop().unwrap();
        if reported.get() == 5 && !sent {
            remote.request_change_channels(&[0.5, -0.5]).unwrap();
            sent = true;
        }
        if sent && server.values().channels()[..2] == [0.5, -0.5] {
            break;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    assert_eq!(reported.get(), 5);
    assert_eq!(remote.num_channels(), 5);
    assert_eq!(server.values().channels(), &[0.5, -0.5, 0.0, 0.0, 0.0]);
}

#[test]
fn poser_requests_and_quirks() {
    let conn = Connection::new_loopback();
    let server = PoserServer::new("Poser0", &conn).unwrap();
    let remote = PoserRemote::on_connection("Poser0", &conn).unwrap();
    let poses = Rc::new(RefCell::new(Vec::new()));
    let p = poses.clone();
    server.on_pose(move |x| p.borrow_mut().push((x.pos, x.quat)));
    let rel = Rc::new(RefCell::new(Vec::new()));
    let r = rel.clone();
    server.on_relative_pose(move |x| r.borrow_mut().push((x.pos, x.quat)));
    let t = TimeVal { sec: 3, usec: 0 };
    let id = [0.0, 0.0, 0.0, 1.0];
    // Position clamped to [-1, 1].
    remote.request_pose(t, [0.5, 2.0, -3.0], id).unwrap();
    assert_eq!(poses.borrow()[0], ([0.5, 1.0, -1.0], id));
    assert_eq!(server.state().time, t);
    // Relative: the remote sends its accumulated pose (0.5,2,-3)+(0.1,0,0); the server adds
    // that to its own clamped pose and calls back with the raw payload.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let rz = [0.0, 0.0, s, s];
    remote
        .request_pose_relative(t, [0.1, 0.0, 0.0], rz)
        .unwrap();
    assert_eq!(rel.borrow()[0], ([0.6, 2.0, -3.0], rz));
    let st = server.state();
    assert_eq!(st.pos, [1.0, 1.0, -1.0]);
    assert_eq!(st.quat, q_mult(rz, id));
    // Velocity clamped; relative velocity adds only x and y and rotates the pose quaternion.
    remote
        .request_pose_velocity(t, [0.5, 5.0, -0.25], id, 0.5)
        .unwrap();
    assert_eq!(server.state().vel, [0.5, 1.0, -0.25]);
    remote
        .request_pose_velocity_relative(t, [0.25, -0.5, 0.5], rz, 0.25)
        .unwrap();
    let st = server.state();
    assert_eq!(st.vel, [0.75, 0.5, -0.25]);
    assert_eq!(st.vel_quat_dt, 0.75);
    assert!((st.quat[2] - 1.0).abs() < 1e-12 && st.quat[3].abs() < 1e-12);
    assert_eq!(
        q_mult([0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 1.0, 0.0]),
        [0.0, 0.0, 0.0, -1.0]
    );
}

#[test]
fn force_device_round_trip_with_tracker_and_button_under_one_name() {
    use vrpn::devices::force::{ForceDeviceRemote, ForceDeviceServer, ForceField, Plane};
    use vrpn::{ButtonRemote, ButtonServer, TrackerRemote, TrackerServer};
    let conn = Connection::new_loopback();
    let tracker = TrackerServer::new("Phantom0", &conn, 1).unwrap();
    let buttons = ButtonServer::new("Phantom0", &conn, 1).unwrap();
    let force = ForceDeviceServer::new("Phantom0", &conn).unwrap();
    let tr = TrackerRemote::on_connection("Phantom0", &conn).unwrap();
    let br = ButtonRemote::on_connection("Phantom0", &conn).unwrap();
    let fr = ForceDeviceRemote::on_connection("Phantom0", &conn).unwrap();
    let forces = Rc::new(RefCell::new(Vec::new()));
    let f = forces.clone();
    fr.on_force(move |x| f.borrow_mut().push(x.force));
    let scps = Rc::new(Cell::new(0));
    let s = scps.clone();
    fr.on_scp(move |x| {
        assert_eq!(x.pos, [0.0, 0.1, 0.0]);
        s.set(s.get() + 1)
    });
    let errs = Rc::new(Cell::new(-1));
    let e = errs.clone();
    fr.on_error(move |x| e.set(x.error_code));
    let planes = Rc::new(RefCell::new(Vec::new()));
    let p = planes.clone();
    force.on_plane(move |(_, pl)| p.borrow_mut().push(*pl));
    let fields = Rc::new(Cell::new(0.0f32));
    let ff = fields.clone();
    force.on_force_field(move |(_, fl)| ff.set(fl.radius));

    let t = TimeVal { sec: 1, usec: 0 };
    tracker
        .report_pose(0, t, [0.0, 0.1, 0.0], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    buttons.set_button(0, true);
    buttons.report_changes().unwrap();
    force.report_force(t, [1.0, -2.0, 0.5]).unwrap();
    force
        .report_scp(t, [0.0, 0.1, 0.0], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    force
        .send_error(vrpn::wire::payload::force::FD_FORCE_ERROR)
        .unwrap();
    assert_eq!(tr.pose(0).unwrap().pos.y, 0.1);
    assert!(br.pressed(0));
    assert_eq!(*forces.borrow(), vec![[1.0, -2.0, 0.5]]);
    assert_eq!(scps.get(), 1);
    assert_eq!(errs.get(), 2);

    let plane = Plane {
        plane: [0.0, 1.0, 0.0, 0.0],
        kspring: 0.8,
        kdamp: 0.001,
        fdyn: 0.3,
        fstat: 0.7,
        plane_index: 0,
        recovery_cycles: 1,
    };
    fr.start_surface(&plane).unwrap();
    assert_eq!(*planes.borrow(), vec![plane]);
    let field = ForceField {
        origin: [0.0; 3],
        force: [0.0; 3],
        jacobian: [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
        radius: 100.0,
    };
    fr.send_force_field(&field).unwrap();
    assert_eq!(fields.get(), 100.0);
}
