//! Imager and ImagerPose: description, frames, regions of every pixel type, throttling and
//! discarded-frame notices, in process and through real sockets on 127.0.0.1.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::imager::{
    BufferLayout, Extent, ImagerPose, ImagerPoseRemote, ImagerPoseServer, ImagerRemote,
    ImagerServer, ValueType,
};
use vrpn::wire::payload::imager as codec;
use vrpn::{Connection, SenderFilter, TimeVal};

/// Runs both connections until `done` or 10 s.
fn pump(conns: &[&Connection], mut done: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(10) {
        for c in conns {
            c.mainloop().unwrap();
        }
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    false
}

fn test_image(cols: usize, rows: usize) -> Vec<u8> {
    (0..cols * rows).map(|i| (i * 7 % 251) as u8).collect()
}

#[test]
fn frames_and_regions_in_process() {
    let conn = Connection::new_loopback();
    let server = ImagerServer::new("Cam0", &conn, 8, 6, 1).unwrap();
    assert_eq!(
        server
            .add_channel("gray", "unsigned8bit", 0.0, 255.0, 0.0, 0.0)
            .unwrap(),
        0
    );
    server
        .add_channel("depth", "meters", 0.0, 10.0, 0.01, 1.0)
        .unwrap();
    let remote = ImagerRemote::on_connection("Cam0", &conn).unwrap();
    let image = test_image(8, 6);
    let received = Rc::new(RefCell::new(vec![0u8; 8 * 6]));
    let floats = Rc::new(RefCell::new(Vec::new()));
    let (r, f) = (received.clone(), floats.clone());
    remote.on_region(move |reg| match reg.value_type {
        ValueType::U8 => reg
            .read_into(&mut r.borrow_mut()[..], &BufferLayout::packed(8, 6))
            .unwrap(),
        ValueType::F32 => f.borrow_mut().push((reg.extent, reg.get_2d::<f32>(2, 5))),
        _ => panic!("unexpected type"),
    });
    let ends = Rc::new(Cell::new(0));
    let e = ends.clone();
    remote.on_end_frame(move |_| e.set(e.get() + 1));

    // No description yet: regions are not delivered (C++ rule). The first region sends it.
    let whole = Extent::whole(8, 6, 1);
    let t = TimeVal { sec: 100, usec: 5 };
    assert!(server.send_begin_frame(&whole, Some(t)).unwrap());
    assert_eq!(remote.last_begin_frame(), None);
    let layout = BufferLayout::packed(8, 6);
    assert!(server
        .send_region(0, &Extent::rect(0, 7, 0, 2), &image, &layout, None)
        .unwrap());
    let d = remote
        .description()
        .expect("description sent before the first region");
    assert_eq!((d.cols, d.rows, d.depth, d.channels), (8, 6, 1, 2));
    let c1 = remote.channel(1).unwrap();
    assert_eq!(c1.name.as_str(), Some("depth"));
    assert_eq!((c1.scale, c1.offset), (0.01, 1.0));
    // Scale 0 became 1, as in C++.
    assert_eq!(remote.channel(0).unwrap().scale, 1.0);
    assert_eq!(remote.channel_index("depth"), Some(1));
    assert!(server
        .send_region(0, &Extent::rect(0, 7, 3, 5), &image, &layout, None)
        .unwrap());
    // A float region from a packed buffer of its own.
    let vals: Vec<f32> = (0..6).map(|i| i as f32 * 0.5).collect();
    assert!(server
        .send_region_packed(1, &Extent::rect(2, 4, 4, 5), &vals, None)
        .unwrap());
    assert!(server.send_end_frame(&whole, Some(t)).unwrap());
    conn.mainloop().unwrap();

    assert_eq!(&received.borrow()[..], &image[..]);
    let fl = floats.borrow();
    assert_eq!(fl.len(), 1);
    assert_eq!(fl[0].0, Extent::rect(2, 4, 4, 5));
    // (2,5) is the first pixel of the region's second row: index 3.
    assert_eq!(fl[0].1, Some(1.5));
    assert_eq!(ends.get(), 1);
    let end = remote.take_end_frame().unwrap();
    assert_eq!((end.seq, end.time, end.extent), (1, t, whole));
    assert_eq!(remote.take_end_frame(), None);
    assert_eq!(remote.regions_received(), 3);
    assert_eq!(remote.bad_messages(), 0);
}

#[test]
fn invalid_requests_are_errors_not_panics() {
    let conn = Connection::new_loopback();
    let server = ImagerServer::new("Cam0", &conn, 4, 4, 1).unwrap();
    server.add_channel("c", "", 0.0, 1.0, 1.0, 0.0).unwrap();
    let img = [0u16; 16];
    let layout = BufferLayout::packed(4, 4);
    // Unknown channel, extent outside the image, reversed extent, short buffer.
    assert!(server
        .send_region(1, &Extent::rect(0, 3, 0, 3), &img, &layout, None)
        .is_err());
    assert!(server
        .send_region(0, &Extent::rect(0, 4, 0, 3), &img, &layout, None)
        .is_err());
    assert!(server
        .send_region(0, &Extent::rect(2, 1, 0, 3), &img, &layout, None)
        .is_err());
    assert!(server
        .send_region(0, &Extent::rect(0, 3, 0, 3), &img[..15], &layout, None)
        .is_err());
    assert!(server
        .send_begin_frame(&Extent::rect(0, 0, 0, 9), None)
        .is_err());
    assert!(server.set_resolution(0, 4, 1).is_err());
    assert!(server
        .add_channel(&"x".repeat(100), "", 0.0, 1.0, 1.0, 0.0)
        .is_err());
    // A region larger than one message holds.
    let big = ImagerServer::new("Big", &conn, 400, 200, 1).unwrap();
    big.add_channel("c", "", 0.0, 1.0, 1.0, 0.0).unwrap();
    let pixels = vec![0u8; 400 * 200];
    let err = big
        .send_region(
            0,
            &Extent::rect(0, 399, 0, 199),
            &pixels,
            &BufferLayout::packed(400, 200),
            None,
        )
        .unwrap_err();
    assert!(err.to_string().contains("exceeds"), "{err}");
    // 159 rows of 400 8-bit pixels fit (63 600 ≤ 63 960).
    assert!(big
        .send_region(
            0,
            &Extent::rect(0, 399, 0, 158),
            &pixels,
            &BufferLayout::packed(400, 200),
            None
        )
        .unwrap());
}

#[test]
fn remote_ignores_malformed_regions() {
    let conn = Connection::new_loopback();
    let server = ImagerServer::new("Cam0", &conn, 4, 4, 1).unwrap();
    server.add_channel("c", "", 0.0, 1.0, 1.0, 0.0).unwrap();
    let remote = ImagerRemote::on_connection("Cam0", &conn).unwrap();
    let seen = Rc::new(Cell::new(0));
    let s = seen.clone();
    remote.on_region(move |_| s.set(s.get() + 1));
    server.send_description().unwrap();
    let u8_type = conn.register_type(codec::REGION_U8).unwrap();
    let t = conn.now().wall;
    // Channel 3 does not exist; a truncated region; an unknown value type.
    let bad: [&[u8]; 3] = [
        &[0, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 7],
        &[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 3, 0, 1, 1, 2],
        &[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 9, 1],
    ];
    for p in bad {
        conn.pack_message(t, u8_type, server.sender(), p, vrpn::ServiceClass::RELIABLE)
            .unwrap();
    }
    assert_eq!(seen.get(), 0);
    assert_eq!(remote.bad_messages(), 3);
}

#[test]
fn throttle_drops_frames_and_reports_them_over_tcp() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = srv.local_port().unwrap();
    let server = ImagerServer::new("Cam0", &srv, 16, 16, 1).unwrap();
    server
        .add_channel("gray", "", 0.0, 255.0, 1.0, 0.0)
        .unwrap();
    let remote = ImagerRemote::new(&format!("Cam0@127.0.0.1:{port}")).unwrap();
    let cli = remote.connection().clone();
    let ends = Rc::new(RefCell::new(Vec::new()));
    let discarded = Rc::new(RefCell::new(Vec::new()));
    let (e, d) = (ends.clone(), discarded.clone());
    remote.on_end_frame(move |f| e.borrow_mut().push(f.seq));
    remote.on_discarded_frames(move |n| d.borrow_mut().push(n.count));
    // The description arrives when the client connects.
    assert!(pump(&[&srv, &cli], || remote.description().is_some()));
    remote.throttle_sender(2).unwrap();
    assert!(pump(&[&srv, &cli], || server.frames_to_send() == 2));
    let image = test_image(16, 16);
    let whole = Extent::whole(16, 16, 1);
    let layout = BufferLayout::packed(16, 16);
    let mut sent = Vec::new();
    for _ in 0..5 {
        let go = server.send_begin_frame(&whole, None).unwrap();
        let region = server
            .send_region(0, &whole, &image, &layout, None)
            .unwrap();
        let end = server.send_end_frame(&whole, None).unwrap();
        assert_eq!(go, region);
        assert_eq!(go, end);
        sent.push(go);
    }
    assert_eq!(sent, [true, true, false, false, false]);
    assert!(pump(&[&srv, &cli], || ends.borrow().len() == 2));
    // Lift the limit: the next frame is preceded by the notice of the 3 dropped.
    remote.throttle_sender(-1).unwrap();
    assert!(pump(&[&srv, &cli], || server.frames_to_send() == -1));
    assert!(server.send_begin_frame(&whole, None).unwrap());
    assert!(server
        .send_region(0, &whole, &image, &layout, None)
        .unwrap());
    assert!(server.send_end_frame(&whole, None).unwrap());
    assert!(pump(&[&srv, &cli], || ends.borrow().len() == 3));
    assert_eq!(*discarded.borrow(), vec![3]);
    assert_eq!(remote.frames_discarded(), 3);
    assert_eq!(remote.regions_received(), 3);
    // The last client leaving lifts a throttle.
    remote.throttle_sender(0).unwrap();
    assert!(pump(&[&srv, &cli], || server.frames_to_send() == 0));
    drop(remote);
    drop(cli);
    assert!(pump(&[&srv], || server.frames_to_send() == -1));
}

#[test]
fn u16_and_float_regions_cross_tcp_exactly() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = srv.local_port().unwrap();
    let server = ImagerServer::new("Cam1", &srv, 300, 120, 2).unwrap();
    server
        .add_channel("raw", "counts", 0.0, 65535.0, 1.0, 0.0)
        .unwrap();
    server
        .add_channel("temp", "K", 0.0, 400.0, 1.0, 0.0)
        .unwrap();
    let remote = ImagerRemote::new(&format!("Cam1@127.0.0.1:{port}")).unwrap();
    let cli = remote.connection().clone();
    let (cols, rows, depth) = (300usize, 120usize, 2usize);
    let raw: Vec<u16> = (0..cols * rows * depth).map(|i| (i * 31) as u16).collect();
    let temp: Vec<f32> = (0..cols * rows).map(|i| i as f32 / 7.0).collect();
    let got_raw = Rc::new(RefCell::new(vec![0u16; raw.len()]));
    let got_temp = Rc::new(RefCell::new(vec![0f32; temp.len()]));
    let (gr, gt) = (got_raw.clone(), got_temp.clone());
    remote.on_region(move |r| {
        let layout = BufferLayout::packed(cols, rows);
        if r.channel == 0 {
            r.read_into(&mut gr.borrow_mut()[..], &layout).unwrap();
        } else {
            r.read_into(&mut gt.borrow_mut()[..], &layout).unwrap();
        }
    });
    assert!(pump(&[&srv, &cli], || remote.description().is_some()));
    let layout = BufferLayout::packed(cols, rows);
    // 16-bit: 100 rows of 300 is 30000 ≤ 31980 per region; depth 1 in its own regions.
    for d in 0..2u16 {
        for r0 in [0u16, 100] {
            let e = Extent {
                c_min: 0,
                c_max: 299,
                r_min: r0,
                r_max: (r0 + 99).min(119),
                d_min: d,
                d_max: d,
            };
            assert!(server.send_region(0, &e, &raw, &layout, None).unwrap());
        }
    }
    for r0 in (0..120u16).step_by(50) {
        let e = Extent::rect(0, 299, r0, (r0 + 49).min(119));
        assert!(server.send_region(1, &e, &temp, &layout, None).unwrap());
    }
    assert!(pump(&[&srv, &cli], || remote.regions_received() == 7));
    assert_eq!(*got_raw.borrow(), raw);
    assert_eq!(*got_temp.borrow(), temp);
}

#[test]
fn wire_bytes_of_a_region_message() {
    // What the server puts on the wire, read by a raw handler: header big-endian, pixels
    // little-endian, packed columns fastest.
    let conn = Connection::new_loopback();
    let server = ImagerServer::new("Cam0", &conn, 4, 4, 1).unwrap();
    server.add_channel("c", "", 0.0, 1.0, 1.0, 0.0).unwrap();
    let u16_type = conn.register_type(codec::REGION_U16).unwrap();
    let payloads = Rc::new(RefCell::new(Vec::new()));
    let p = payloads.clone();
    conn.register_handler(u16_type, SenderFilter::Any, move |m| {
        p.borrow_mut().push(m.payload.to_vec())
    });
    let img: Vec<u16> = (0..16).map(|i| 0x0100 + i).collect();
    server
        .send_region(
            0,
            &Extent::rect(1, 2, 2, 3),
            &img,
            &BufferLayout::packed(4, 4),
            None,
        )
        .unwrap();
    let p = payloads.borrow();
    assert_eq!(
        p[0],
        [
            0, 0, 0, 0, 0, 0, 0, 2, 0, 3, 0, 1, 0, 2, 0,
            4, // header: ch 0, d 0..0, r 2..3, c 1..2, u16
            0x09, 0x01, 0x0a, 0x01, 0x0d, 0x01, 0x0e, 0x01 // pixels 9, 10, 13, 14
        ]
    );
}

#[test]
fn imager_pose_description_and_pixel_centres() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = srv.local_port().unwrap();
    let pose = ImagerPose {
        origin: [0.0, 0.0, 0.0],
        d_col: [0.2, 0.0, 0.0],
        d_row: [0.0, 0.1, 0.0],
        d_depth: [0.0, 0.0, 0.0],
    };
    let server = ImagerPoseServer::new("Cam0", &srv, pose).unwrap();
    let remote = ImagerPoseRemote::new(&format!("Cam0@127.0.0.1:{port}")).unwrap();
    let cli = remote.connection().clone();
    assert!(pump(&[&srv, &cli], || remote.pose().is_some()));
    assert_eq!(remote.pose().unwrap().pose, pose);
    let moved = ImagerPose {
        origin: [1.0, 2.0, 3.0],
        ..pose
    };
    server.set_pose(moved).unwrap();
    assert!(pump(&[&srv, &cli], || remote.pose().unwrap().pose == moved));
    // 4 × 2 pixels: the centre of (1, 1) is 1.5/4 of the width and 1.5/2 of the height.
    let c = moved.pixel_center(4, 2, 1, 1, 1, 0).unwrap();
    assert!((c[0] - (1.0 + 0.2 * 1.5 / 4.0)).abs() < 1e-12);
    assert!((c[1] - (2.0 + 0.1 * 1.5 / 2.0)).abs() < 1e-12);
    assert_eq!(moved.pixel_center(4, 2, 1, 4, 0, 0), None);
}
