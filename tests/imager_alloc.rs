//! An imager stream allocates nothing once set up: frames of regions (8-bit, 16-bit and
//! float, whole-image buffers and packed ones) sent by an `ImagerServer` and read into the
//! application's image by an `ImagerRemote`'s callback, in process and over TCP on
//! 127.0.0.1. Checked with a counting global allocator.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use counting_alloc::allocations_in;
use vrpn::devices::imager::{BufferLayout, Extent, ImagerRemote, ImagerServer, ValueType};
use vrpn::Connection;

const COLS: usize = 128;
const ROWS: usize = 96;

/// A server with a gray 8-bit, a 16-bit and a float channel, and a remote that copies every
/// region into images of its own.
struct Stream {
    server: ImagerServer,
    remote: ImagerRemote,
    gray: Vec<u8>,
    raw: Vec<u16>,
    temp: Vec<f32>,
    /// The remote's images.
    got_gray: Rc<RefCell<Vec<u8>>>,
    got_raw: Rc<RefCell<Vec<u16>>>,
    got_temp: Rc<RefCell<Vec<f32>>>,
    ends: Rc<Cell<u64>>,
}

impl Stream {
    fn new(server_conn: &Connection, remote: ImagerRemote) -> Stream {
        let server = ImagerServer::new("Cam0", server_conn, COLS as i32, ROWS as i32, 1).unwrap();
        server
            .add_channel("gray", "", 0.0, 255.0, 1.0, 0.0)
            .unwrap();
        server
            .add_channel("raw", "", 0.0, 65535.0, 1.0, 0.0)
            .unwrap();
        server
            .add_channel("temp", "K", 0.0, 400.0, 1.0, 0.0)
            .unwrap();
        let got_gray = Rc::new(RefCell::new(vec![0u8; COLS * ROWS]));
        let got_raw = Rc::new(RefCell::new(vec![0u16; COLS * ROWS]));
        let got_temp = Rc::new(RefCell::new(vec![0f32; COLS * ROWS]));
        let (g, r, t) = (got_gray.clone(), got_raw.clone(), got_temp.clone());
        remote.on_region(move |reg| {
            let layout = BufferLayout::packed(COLS, ROWS);
            match reg.value_type {
                ValueType::U8 => reg.read_into(&mut g.borrow_mut()[..], &layout),
                ValueType::U16 => reg.read_into(&mut r.borrow_mut()[..], &layout),
                _ => reg.read_into(&mut t.borrow_mut()[..], &layout),
            }
            .unwrap();
        });
        let ends = Rc::new(Cell::new(0));
        let e = ends.clone();
        remote.on_end_frame(move |_| e.set(e.get() + 1));
        Stream {
            server,
            remote,
            gray: vec![0; COLS * ROWS],
            raw: vec![0; COLS * ROWS],
            temp: vec![0.0; COLS * ROWS],
            got_gray,
            got_raw,
            got_temp,
            ends,
        }
    }

    /// Changes the images and sends one frame: the gray and 16-bit channels in halves from
    /// the whole images, the float channel as packed strips.
    fn send_frame(&mut self, n: u64) {
        for (i, v) in self.gray.iter_mut().enumerate() {
            *v = (i as u64 + n) as u8;
        }
        for (i, v) in self.raw.iter_mut().enumerate() {
            *v = (i as u64 * 3 + n) as u16;
        }
        for (i, v) in self.temp.iter_mut().enumerate() {
            *v = i as f32 + n as f32;
        }
        let whole = Extent::whole(COLS as u16, ROWS as u16, 1);
        let layout = BufferLayout::packed(COLS, ROWS);
        let s = &self.server;
        assert!(s.send_begin_frame(&whole, None).unwrap());
        let half = (ROWS / 2) as u16;
        for (r0, r1) in [(0, half - 1), (half, ROWS as u16 - 1)] {
            let e = Extent::rect(0, COLS as u16 - 1, r0, r1);
            assert!(s.send_region(0, &e, &self.gray, &layout, None).unwrap());
            assert!(s.send_region(1, &e, &self.raw, &layout, None).unwrap());
        }
        let strip = 24;
        for r0 in (0..ROWS).step_by(strip) {
            let e = Extent::rect(0, COLS as u16 - 1, r0 as u16, (r0 + strip - 1) as u16);
            let data = &self.temp[r0 * COLS..(r0 + strip) * COLS];
            assert!(s.send_region_packed(2, &e, data, None).unwrap());
        }
        assert!(s.send_end_frame(&whole, None).unwrap());
    }

    fn received_all(&self) -> bool {
        *self.got_gray.borrow() == self.gray
            && *self.got_raw.borrow() == self.raw
            && *self.got_temp.borrow() == self.temp
    }
}

#[test]
fn in_process_frames_do_not_allocate() {
    let conn = Connection::new_loopback();
    let remote = ImagerRemote::on_connection("Cam0", &conn).unwrap();
    let mut s = Stream::new(&conn, remote);
    for n in 0..20 {
        s.send_frame(n);
        conn.mainloop().unwrap();
    }
    assert!(s.received_all());
    let before = s.ends.get();
    let frames = 500;
    let allocs = allocations_in(|| {
        for n in 0..frames {
            s.send_frame(1000 + n);
            conn.mainloop().unwrap();
        }
    });
    assert_eq!(s.ends.get() - before, frames);
    assert!(s.received_all());
    assert_eq!(s.remote.bad_messages(), 0);
    assert_eq!(allocs, 0, "allocations while streaming frames in process");
}

#[test]
fn tcp_frames_do_not_allocate() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    srv.on_notice(|_| {});
    let port = srv.local_port().unwrap();
    let remote = ImagerRemote::new(&format!("Cam0@127.0.0.1:{port}")).unwrap();
    let cli = remote.connection().clone();
    let mut s = Stream::new(&srv, remote);
    let pump_until = |done: &dyn Fn() -> bool| {
        let start = Instant::now();
        while !done() {
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "frame not delivered"
            );
            srv.mainloop().unwrap();
            cli.mainloop().unwrap();
        }
    };
    pump_until(&|| s.remote.description().is_some());
    // Warm up: buffers reach their working sizes, the ping cycle has its pong.
    for n in 0..50 {
        let want = s.ends.get() + 1;
        s.send_frame(n);
        pump_until(&|| s.ends.get() == want);
    }
    assert!(s.received_all());
    let frames = 300;
    let before = s.ends.get();
    let allocs = allocations_in(|| {
        for n in 0..frames {
            let want = s.ends.get() + 1;
            s.send_frame(1000 + n);
            pump_until(&|| s.ends.get() == want);
        }
    });
    assert_eq!(s.ends.get() - before, frames);
    assert!(s.received_all());
    assert_eq!(allocs, 0, "allocations while streaming frames over TCP");
}
