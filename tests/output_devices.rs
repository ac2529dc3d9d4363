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
    let mut remote = PoserRemote::on_connection("Poser0", &conn).unwrap();
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
