//! A 60 Hz frame loop that polls: one `mainloop()` per frame, then the latest state of a
//! tracker and a button read with `take_*`, which say whether something new arrived since
//! the last frame; connection state changes are shown as they happen.
//!
//! Against a running server (`cargo run --release --bin vrpn_server -- -f vrpn.cfg.sample`):
//! `cargo run --example frame_loop -- Tracker0@localhost Button0@localhost`
//!
//! Stand-alone, with a server in the same thread that moves a tracker in a circle, clicks a
//! button once a second and restarts half-way: `cargo run --example frame_loop -- --demo`

use std::cell::Cell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::{
    ButtonRemote, ButtonServer, Connection, ConnectionState, Limits, TrackerRemote, TrackerServer,
};

const FRAME: Duration = Duration::from_micros(16_667);

fn main() -> Result<(), vrpn::Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let demo = args.iter().any(|a| a == "--demo");
    let mut names = args.iter().filter(|a| !a.starts_with("--"));

    // The demo's server: a real server connection on a free port of 127.0.0.1.
    let mut server = demo.then(DemoServer::start).transpose()?;
    let (tracker_name, button_name) = match &server {
        Some(s) => (
            format!("Tracker0@127.0.0.1:{}", s.port),
            format!("Button0@127.0.0.1:{}", s.port),
        ),
        None => (
            names.next().cloned().unwrap_or("Tracker0@localhost".into()),
            names.next().cloned().unwrap_or("Button0@localhost".into()),
        ),
    };

    // Retry every 250 ms instead of every second: limits go through the builder. The demo's
    // server shares this process's clock and answers only once per frame (which would bias
    // a clock-offset estimate by half a frame), so the demo turns clock sync off.
    let tracker = TrackerRemote::builder(&tracker_name)
        .limits(Limits {
            retry_interval: Duration::from_millis(250),
            clock_sync: if demo {
                None
            } else {
                Limits::default().clock_sync
            },
            ..Limits::default()
        })
        .build()?;
    // Same location text: the button shares the tracker's connection (and its limits).
    let button = ButtonRemote::new(&button_name)?;
    let state = Rc::new(Cell::new(tracker.connection().state()));
    let s = state.clone();
    tracker.connection().on_state_change(move |now| {
        println!("connection: {:?} -> {now:?}", s.get());
        s.set(*now);
    });

    let frames = if demo { 6 * 60 } else { u64::MAX };
    let mut next = Instant::now();
    let (mut fresh_frames, mut clicks) = (0u64, 0u32);
    for frame in 0..frames {
        if let Some(s) = server.as_mut() {
            s.step(frame)?;
        }
        // One call serves every remote on the connection (the button too).
        tracker.mainloop()?;

        // Poll: a pose that is new this frame, or none (then `pose(0)` still has the last).
        if let Some(p) = tracker.take_pose(0) {
            fresh_frames += 1;
            if frame % 60 == 0 {
                // `time` is the server's stamp in local time (clock sync), `arrival` when
                // the pass that read it ran.
                let transit_ms = p.arrival.seconds_since(p.time) * 1e3;
                println!(
                    "frame {frame}: pose #{} at ({:+.2}, {:+.2}, {:+.2}), arrived {transit_ms:.2} ms after its stamp",
                    p.seq, p.pos.x, p.pos.y, p.pos.z
                );
            }
        } else if state.get() != ConnectionState::Connected && frame % 60 == 0 {
            println!("frame {frame}: no data ({:?})", state.get());
        }
        // A click between two frames is not lost even if the button is up again.
        let n = button.take_presses(0);
        if n > 0 {
            clicks += n;
            println!(
                "frame {frame}: button 0 clicked (held now: {})",
                button.pressed(0)
            );
        }

        // ... draw the frame here ...
        next += FRAME;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    println!("{fresh_frames} frames had a new pose; {clicks} clicks");
    Ok(())
}

/// The demo's server side, run from the same frame loop: it reports a pose every frame and
/// a click every second, and goes away for half a second after three seconds.
struct DemoServer {
    port: u16,
    conn: Option<(Connection, TrackerServer, ButtonServer)>,
}

impl DemoServer {
    fn start() -> Result<DemoServer, vrpn::Error> {
        let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0)?;
        let port = conn.local_port().expect("a server has a port");
        let mut s = DemoServer { port, conn: None };
        s.open(conn)?;
        Ok(s)
    }

    fn open(&mut self, conn: Connection) -> Result<(), vrpn::Error> {
        let tracker = TrackerServer::new("Tracker0", &conn, 1)?;
        let button = ButtonServer::new("Button0", &conn, 1)?;
        self.conn = Some((conn, tracker, button));
        Ok(())
    }

    fn step(&mut self, frame: u64) -> Result<(), vrpn::Error> {
        match frame {
            180 => {
                println!("(demo: the server stops)");
                self.conn = None;
            }
            210 => {
                println!("(demo: the server is back)");
                let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), self.port)?;
                self.open(conn)?;
            }
            _ => {}
        }
        let Some((conn, tracker, button)) = &self.conn else {
            return Ok(());
        };
        let now = conn.now().wall;
        let a = frame as f64 / 60.0;
        tracker.report_pose(0usize, now, [a.cos(), a.sin(), 1.5], [0.0, 0.0, 0.0, 1.0])?;
        button.set_timestamp(now);
        button.set_button(0, frame % 60 == 30);
        button.report_changes()?;
        conn.mainloop()
    }
}
