//! The Python button box end to end: the driver in a server loop (in its own thread, on a real
//! TCP port) reading a fake parallel port the test drives, and a TCP client of its Button.
//! Checked against the fake's log: exact changes in order, stamped with the sample that saw
//! them; bouncing contacts; a port that fails and comes back (reported, nothing invented).
//!
//! The fake answers the status reads that `ppdev` would; the `ppdev` ioctls themselves are not
//! exercised here (no parallel port on the test machines).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use vrpn::driver::Interface;
use vrpn::drivers::parport_python::sim::{expected_changes, FakeParport, RELEASED};
use vrpn::drivers::parport_python::PythonButtons;
use vrpn::server::{ServerLoop, SleepPolicy};
use vrpn::sim::rig::{assert_first_byte_stamps, Client, Heard};
use vrpn::{Connection, Now, ServerDevice, TimeVal};

/// The server loop with the box on `port`, in a thread until `stop`; returns its TCP port.
fn serve(port: FakeParport, stop: Arc<AtomicBool>) -> (u16, std::thread::JoinHandle<()>) {
    let (tx, rx) = mpsc::channel();
    let thread = std::thread::spawn(move || {
        let conn = Connection::server(Some([127, 0, 0, 1].into()), 0).unwrap();
        tx.send(conn.local_port().unwrap()).unwrap();
        let device = PythonButtons::new("Button0", port, &conn).unwrap();
        let devices: Vec<Box<dyn ServerDevice>> = vec![Box::new(device)];
        let mut server = ServerLoop::new(
            conn,
            devices,
            SleepPolicy::EventDriven {
                busy_window: Duration::from_millis(2),
                max_block: Duration::from_millis(100),
            },
        );
        server.run(&stop).unwrap();
    });
    (rx.recv_timeout(Duration::from_secs(10)).unwrap(), thread)
}

fn changes(c: &Client, from: usize) -> Vec<((usize, bool), TimeVal)> {
    c.heard()[from..]
        .iter()
        .filter_map(|h| match h {
            Heard::Button {
                button,
                pressed,
                time,
            } => Some(((*button, *pressed), *time)),
            _ => None,
        })
        .collect()
}

fn texts_with(c: &Client, needle: &str) -> usize {
    c.texts_from(0)
        .iter()
        .filter(|t| t.contains(needle))
        .count()
}

#[test]
fn python_box_through_a_server_to_a_client() {
    let port = FakeParport::new("/dev/parport0");
    let stop = Arc::new(AtomicBool::new(false));
    let t0 = Now::read();
    let (tcp, thread) = serve(port.clone(), stop.clone());
    let client = Client::connect("Button0", tcp, &[Interface::Button]).unwrap();
    assert!(client.pump_until(Duration::from_secs(5), |_| port.opens() == 1));
    // The client hears the server: wait for its connection before pressing anything.
    client.pump_until(Duration::from_millis(300), |_| false);

    // 1. Every button, then chords, 40 ms apart; each change stamped with its sample.
    let mut values = Vec::new();
    for bit in [0x10u8, 0x80, 0x20, 0x08, 0x40] {
        values.push(RELEASED ^ bit);
        values.push(RELEASED);
    }
    values.extend([0x80, RELEASED, RELEASED ^ 0x18, RELEASED ^ 0x60, RELEASED]);
    for &v in &values {
        port.set(v);
        client.pump_until(Duration::from_millis(40), |_| false);
    }
    let log = port.log();
    let want = expected_changes(&log);
    assert!(
        client.pump_until(Duration::from_secs(5), |c| changes(c, 0).len()
            >= want.len())
    );
    let got = changes(&client, 0);
    assert_eq!(
        got.iter().map(|g| g.0).collect::<Vec<_>>(),
        want.iter().map(|w| (w.1, w.2)).collect::<Vec<_>>()
    );
    let stamps: Vec<TimeVal> = got.iter().map(|g| g.1).collect();
    let set_at: Vec<_> = want.iter().map(|w| log[w.0].0).collect();
    assert_first_byte_stamps(&stamps, &set_at, t0, Duration::from_millis(250), "Python");

    // 2. A bouncing contact: nothing until it settles, then one change.
    let n = client.len();
    port.set(RELEASED ^ 0x40);
    port.bounce(10_000);
    client.pump_until(Duration::from_millis(300), |_| false);
    port.bounce(0);
    assert!(client.pump_until(Duration::from_secs(2), |c| !changes(c, n).is_empty()));
    client.pump_until(Duration::from_millis(100), |_| false);
    assert_eq!(
        changes(&client, n).iter().map(|g| g.0).collect::<Vec<_>>(),
        [(4, true)]
    );

    // 3. The port fails and is gone a while: reported, nothing reported meanwhile, reopened.
    let n = client.len();
    port.fail_reads(true);
    port.fail_opens(true);
    client.wait_text_or_panic("reading /dev/parport0 failed");
    port.set(RELEASED);
    client.pump_until(Duration::from_millis(1500), |_| false);
    assert!(
        changes(&client, n).is_empty(),
        "nothing while the port is gone"
    );
    port.fail_reads(false);
    port.fail_opens(false);
    assert!(
        client.pump_until(Duration::from_secs(3), |c| texts_with(c, "is open again")
            == 1)
    );
    assert!(client.pump_until(Duration::from_secs(2), |c| !changes(c, n).is_empty()));
    assert_eq!(
        changes(&client, n).iter().map(|g| g.0).collect::<Vec<_>>(),
        [(4, false)]
    );

    stop.store(true, Ordering::Relaxed);
    thread.join().unwrap();
}

trait WaitText {
    fn wait_text_or_panic(&self, needle: &str);
}

impl WaitText for Client {
    fn wait_text_or_panic(&self, needle: &str) {
        assert!(
            self.pump_until(Duration::from_secs(3), |c| texts_with(c, needle) >= 1),
            "no text with {needle:?}: {:?}",
            self.texts_from(0)
        );
    }
}
