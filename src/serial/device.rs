//! A driver on a real port, as a device the server loop runs: the port waits in the server's
//! poll, bytes are handed to the driver with the time the poll woke for them, the driver's
//! requests are carried out, and a port that fails or vanishes is reported and reopened —
//! for every driver alike.
//!
//! A port problem (it cannot be opened, it failed) is reported once per change, never at
//! every retry: as a text message to the clients connected then, to the program through a
//! [`StatusSink`] if one was given, and again to every client that connects while the
//! problem lasts, so that a client started later learns why nothing arrives.

use std::cell::Cell;
use std::io;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::driver::{PortOp, PortOps, SerialDriver};
use super::port::Port;
use crate::connection::Connection;
use crate::connection::ConnectionEvent;
use crate::devices::text::TextSeverity;
use crate::devices::ServerDevice;
use crate::dispatch::SenderId;
use crate::driver::status::{DeviceStatus, OpenFailure, StatusSink};
use crate::net::Reactor;
use crate::time::Now;

/// How often a port that cannot be opened is tried again.
pub const REOPEN_INTERVAL: Duration = Duration::from_secs(1);
/// Bytes read per read call.
const READ_CHUNK: usize = 512;
/// Output the port did not take at once, kept for the next pass (commands are small; a driver
/// that writes more than this to a line that does not drain loses the excess).
const MAX_PENDING_WRITE: usize = 16 * 1024;

/// A port problem, with the text clients were sent about it.
#[derive(Clone, Debug)]
enum Problem {
    CannotOpen(OpenFailure, String),
    Lost(String),
}

impl Problem {
    fn text(&self) -> &str {
        match self {
            Problem::CannotOpen(_, text) | Problem::Lost(text) => text,
        }
    }
}

/// A driver and the port it reads. See the module documentation.
pub struct SerialDevice<D: SerialDriver> {
    driver: D,
    path: String,
    name: String,
    conn: Connection,
    sender: Option<SenderId>,
    reactor: Option<Reactor>,
    port: Option<Port>,
    token: Option<mio::Token>,
    ops: PortOps,
    pending: Vec<u8>,
    buf: Box<[u8; READ_CHUNK]>,
    reopen_at: Option<Instant>,
    /// The port's problem while it lasts, as last reported (not repeated while it stays the
    /// same; sent again to clients that connect meanwhile).
    problem: Option<Problem>,
    /// Set when a client connects: a problem is told to it at the next pass.
    announce: Rc<Cell<bool>>,
    status: Option<StatusSink>,
    /// Times the port was opened.
    opens: u64,
    /// The time of the last pass (to retry output the port did not take).
    last_pass: Option<Instant>,
}

impl<D: SerialDriver> SerialDevice<D> {
    /// Runs `driver` on the port at `path`, reporting problems as texts from the driver's
    /// device on `conn`, and waiting in `conn`'s reactor (a connection without one — loopback —
    /// makes the device read its port on every pass instead). The port opens at the first
    /// pass.
    pub fn new(path: &str, driver: D, conn: &Connection) -> SerialDevice<D> {
        let name = driver.name().to_string();
        SerialDevice {
            sender: conn.register_sender(&name).ok(),
            driver,
            path: path.to_string(),
            name,
            conn: conn.clone(),
            reactor: conn.reactor(),
            port: None,
            token: None,
            ops: PortOps::new(),
            pending: Vec::with_capacity(256),
            buf: Box::new([0; READ_CHUNK]),
            reopen_at: None,
            problem: None,
            announce: {
                let flag = Rc::new(Cell::new(false));
                let f = flag.clone();
                conn.on_event(ConnectionEvent::GotConnection, move || f.set(true));
                flag
            },
            status: None,
            opens: 0,
            last_pass: None,
        }
    }

    /// Also tells `sink` about the port's state changes (for the program to show them).
    pub fn report_status_to(&mut self, sink: StatusSink) {
        self.status = Some(sink);
    }

    /// The driver.
    pub fn driver(&self) -> &D {
        &self.driver
    }

    /// The driver, to change it.
    pub fn driver_mut(&mut self) -> &mut D {
        &mut self.driver
    }

    /// The port's path.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// True while the port is open.
    pub fn is_open(&self) -> bool {
        self.port.is_some()
    }

    /// Times the port was opened (first open included).
    pub fn opens(&self) -> u64 {
        self.opens
    }

    fn text(&self, severity: TextSeverity, text: &str) {
        if let Some(sender) = self.sender {
            let _ = self.conn.send_text(sender, severity, 0, text);
        }
    }

    fn open(&mut self, now: Now) {
        match Port::open(&self.path, self.driver.port_kind()) {
            Ok(port) => {
                if let Some(r) = &self.reactor {
                    match r.register_fd(port.fd(), mio::Interest::READABLE) {
                        Ok(t) => self.token = Some(t),
                        Err(e) => {
                            self.failed_to_open(now, e);
                            return;
                        }
                    }
                }
                if self.problem.take().is_some() || self.opens > 0 {
                    let text = format!("serial port {} is open again", self.path);
                    self.text(TextSeverity::Normal, &text);
                    self.tell(DeviceStatus::Opened {
                        port: self.path.clone(),
                    });
                }
                self.port = Some(port);
                self.opens += 1;
                self.reopen_at = None;
                self.pending.clear();
                self.driver.opened(now, &mut self.ops);
                self.carry_out(now);
            }
            Err(e) => self.failed_to_open(now, e),
        }
    }

    fn tell(&self, status: DeviceStatus) {
        if let Some(sink) = &self.status {
            sink(&self.name, &status);
        }
    }

    fn failed_to_open(&mut self, now: Now, e: io::Error) {
        self.reopen_at = Some(now.mono + REOPEN_INTERVAL);
        let reason = OpenFailure::from_io(&e);
        if matches!(&self.problem, Some(Problem::CannotOpen(r, _)) if *r == reason) {
            return;
        }
        let text = format!(
            "cannot open serial port {} for {}: {reason}; trying again every {:?}",
            self.path, self.name, REOPEN_INTERVAL
        );
        self.text(TextSeverity::Error, &text);
        self.tell(DeviceStatus::CannotOpen {
            port: self.path.clone(),
            reason: reason.clone(),
        });
        self.problem = Some(Problem::CannotOpen(reason, text));
    }

    fn close(&mut self) {
        if let Some(port) = self.port.take() {
            if let (Some(r), Some(t)) = (&self.reactor, self.token.take()) {
                r.deregister_fd(port.fd(), t);
            }
        }
        self.pending.clear();
    }

    /// The port failed or vanished: say so, tell the driver, and reopen on schedule.
    fn fail(&mut self, now: Now, why: &str) {
        self.close();
        self.driver.closed(now);
        let text = format!(
            "serial port {} of {} failed ({why}); reopening it when it comes back",
            self.path, self.name
        );
        self.text(TextSeverity::Error, &text);
        self.tell(DeviceStatus::Lost {
            port: self.path.clone(),
            reason: why.to_string(),
        });
        self.problem = Some(Problem::Lost(text));
        self.reopen_at = Some(now.mono + REOPEN_INTERVAL);
    }

    /// Carries out the driver's requests, in order.
    fn carry_out(&mut self, now: Now) {
        let mut reopen = false;
        let mut failure = None;
        if let Some(port) = self.port.as_mut() {
            for op in self.ops.ops().iter().copied() {
                match op {
                    PortOp::Write { start, len } => {
                        let bytes = self.ops.write_bytes(start, len);
                        let mut done = 0;
                        if self.pending.is_empty() {
                            match port.write(bytes) {
                                Ok(n) => done = n,
                                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                                Err(e) => {
                                    failure = Some(e.to_string());
                                    break;
                                }
                            }
                        }
                        let rest = &bytes[done..];
                        let room = MAX_PENDING_WRITE.saturating_sub(self.pending.len());
                        self.pending
                            .extend_from_slice(&rest[..rest.len().min(room)]);
                    }
                    PortOp::FlushInput => {
                        let _ = port.flush_input();
                    }
                    PortOp::FlushOutput => {
                        self.pending.clear();
                        let _ = port.flush_output();
                    }
                    PortOp::SetRts(on) => port.set_rts(on),
                    PortOp::SetDtr(on) => port.set_dtr(on),
                    PortOp::Reopen => reopen = true,
                    PortOp::SetBaud(baud) => {
                        if let Err(e) = port.set_baud(baud) {
                            failure = Some(format!("cannot set {baud} baud: {e}"));
                            break;
                        }
                    }
                }
            }
        }
        self.ops.clear();
        if let Some(why) = failure {
            self.fail(now, &why);
        } else if reopen {
            self.close();
            self.open(now);
        }
    }

    /// Writes output the port did not take before.
    fn write_pending(&mut self, now: Now) {
        let Some(port) = self.port.as_ref() else {
            return;
        };
        if self.pending.is_empty() {
            return;
        }
        match port.write(&self.pending) {
            Ok(n) => {
                self.pending.drain(..n);
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
            Err(e) => self.fail(now, &e.to_string()),
        }
    }

    /// Reads everything waiting, handing it to the driver with the time the poll woke for it.
    ///
    /// Only the bytes that were waiting when the poll woke carry its time: on a loaded machine
    /// the read can come milliseconds after the wake, and bytes that came meanwhile (the next
    /// record's head) are handed over apart, stamped with a clock read after the read that
    /// found them — never earlier than they came.
    ///
    /// With `even_if_not_woken` it also reads when the poll did not report the port readable
    /// (stamped with `now`): before a deadline acts on silence, bytes that came while the
    /// process was not running (a loaded machine) are taken first, so a device that spoke in
    /// time is not treated as silent.
    fn read_all(&mut self, now: Now, even_if_not_woken: bool) {
        let (arrived, waiting) = match (&self.reactor, self.token) {
            (Some(r), Some(t)) => {
                let ready = r.take(t);
                if !ready.readable && !even_if_not_woken {
                    return;
                }
                match ready.woke {
                    Some(woke) => (woke, ready.waiting),
                    None => (now, None),
                }
            }
            // No poll (a loopback connection): read every pass, stamped with the pass time.
            _ => (now, None),
        };
        // Bytes still to be read that were waiting at the wake (unknown: all of them).
        let mut from_wake = waiting.unwrap_or(usize::MAX);
        let opens = self.opens;
        loop {
            let Some(port) = self.port.as_ref() else {
                return;
            };
            match port.read(&mut self.buf[..]) {
                Ok(0) => {
                    self.fail(now, "end of file");
                    return;
                }
                Ok(n) => {
                    let early = n.min(from_wake);
                    from_wake -= early;
                    if early > 0 {
                        self.driver
                            .received(&self.buf[..early], arrived, &mut self.ops);
                        self.carry_out(now);
                    }
                    // The rest came after the wake (unless the driver's request closed or
                    // reopened the port: then they belong to a line that is gone).
                    if early < n && self.port.is_some() && self.opens == opens {
                        let later = Now::read();
                        self.driver
                            .received(&self.buf[early..n], later, &mut self.ops);
                        self.carry_out(now);
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => {
                    // A pseudo-terminal whose master closed reads EIO; an unplugged USB
                    // adapter, ENODEV or EIO.
                    self.fail(now, &e.to_string());
                    return;
                }
            }
        }
    }
}

impl<D: SerialDriver> ServerDevice for SerialDevice<D> {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        self.last_pass = Some(now.mono);
        if self.announce.replace(false) && self.port.is_none() {
            if let Some(p) = &self.problem {
                self.text(TextSeverity::Error, p.text());
            }
        }
        if self.port.is_none() && self.reopen_at.map_or(true, |t| now.mono >= t) {
            self.open(now);
        }
        if self.port.is_some() {
            self.read_all(now, false);
        }
        if self.port.is_some() && self.driver.next_deadline().is_some_and(|d| now.mono >= d) {
            self.read_all(now, true);
        }
        if self.port.is_some() && self.driver.next_deadline().is_some_and(|d| now.mono >= d) {
            self.driver.poll(now, &mut self.ops);
            self.carry_out(now);
        }
        self.write_pending(now);
    }

    fn next_deadline(&self) -> Option<Instant> {
        let retry_write = (!self.pending.is_empty())
            .then(|| self.last_pass.map(|t| t + Duration::from_millis(1)))
            .flatten();
        [
            if self.port.is_some() {
                self.driver.next_deadline()
            } else {
                None
            },
            if self.port.is_none() {
                self.reopen_at
            } else {
                None
            },
            retry_write,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}

#[cfg(all(test, feature = "sim"))]
mod tests {
    use std::cell::RefCell;
    use std::net::Ipv4Addr;

    use super::*;
    use crate::serial::{PortKind, PortSettings};
    use crate::sim::{DeviceModel, PtyDevice};

    /// Sends what it is given, at once.
    struct Speaker(Vec<u8>);

    impl DeviceModel for Speaker {
        fn receive(&mut self, _bytes: &[u8], _now: Now) {}
        fn transmit(&mut self, _now: Now, out: &mut Vec<u8>) {
            out.append(&mut self.0);
        }
        fn next_deadline(&self) -> Option<Instant> {
            None
        }
    }

    /// Keeps every byte it is handed with the time it came with.
    struct Recorder(Rc<RefCell<Vec<(u8, Now)>>>);

    impl SerialDriver for Recorder {
        fn name(&self) -> &str {
            "Recorder"
        }
        fn port_kind(&self) -> PortKind {
            PortKind::Serial(PortSettings::n81(115_200))
        }
        fn opened(&mut self, _now: Now, _port: &mut PortOps) {}
        fn received(&mut self, bytes: &[u8], arrived: Now, _port: &mut PortOps) {
            self.0
                .borrow_mut()
                .extend(bytes.iter().map(|&b| (b, arrived)));
        }
        fn poll(&mut self, _now: Now, _port: &mut PortOps) {}
        fn next_deadline(&self) -> Option<Instant> {
            None
        }
        fn closed(&mut self, _now: Now) {}
    }

    /// A server slow to read after its poll woke (a loaded machine) finds the next record's
    /// head behind the bytes it woke for: those bytes keep the wake time, the later ones are
    /// not dated back to it (before they existed).
    #[test]
    fn bytes_that_came_after_the_wake_are_not_dated_back_to_it() {
        let dir = std::env::temp_dir().join(format!("vrpn-serial-wake-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let link = dir.join("tty");
        let mut line = PtyDevice::open(Speaker(Vec::new()), &link).unwrap();
        let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let reactor = conn.reactor().expect("a server connection polls");
        let got = Rc::default();
        let mut dev = SerialDevice::new(link.to_str().unwrap(), Recorder(Rc::clone(&got)), &conn);
        dev.mainloop(Now::read());
        assert!(dev.is_open());

        line.model.0.extend_from_slice(b"abc");
        line.step(Now::read()).unwrap();
        let give_up = Instant::now() + Duration::from_secs(10);
        while !reactor.timed_pending() {
            assert!(Instant::now() < give_up, "the port never turned readable");
            reactor.wait(None, Duration::from_millis(10)).unwrap();
        }
        // The poll has woken; the next record's head comes before the server reads.
        std::thread::sleep(Duration::from_millis(5));
        let second = Now::read();
        line.model.0.extend_from_slice(b"XYZ");
        line.step(second).unwrap();
        std::thread::sleep(Duration::from_millis(20));
        dev.mainloop(Now::read());

        let got = got.borrow();
        let bytes: Vec<u8> = got.iter().map(|&(b, _)| b).collect();
        assert_eq!(bytes, b"abcXYZ");
        let stamp = |b: u8| got.iter().find(|g| g.0 == b).unwrap().1;
        assert!(stamp(b'a').wall < second.wall, "{got:?}");
        assert!(
            stamp(b'X').wall >= second.wall,
            "dated before it was written: {got:?}"
        );
        drop(line);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
