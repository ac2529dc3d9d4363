//! The end-to-end rig of a driver test: a `vrpn_server` child process serving one
//! configuration, and a TCP client that records, in order, everything it hears from one
//! device name. With a [`SimulatedDevice`](super::SimulatedDevice) on the configured port this
//! is a driver under test through a real server to a real client.
//!
//! ```no_run
//! # use std::time::Duration;
//! # use vrpn::sim::rig::{Client, ServerProcess};
//! # use vrpn::driver::Interface;
//! // In a test: the path comes from Cargo (`env!("CARGO_BIN_EXE_vrpn_server")`).
//! let server = ServerProcess::start("target/release/vrpn_server".as_ref(),
//!     "vrpn_Tracker_NULL Tracker0 1 60\n").unwrap();
//! let client = Client::connect("Tracker0", server.port(), &[Interface::Tracker]).unwrap();
//! client.wait_until(Duration::from_secs(5), "ten poses", &server, |c| c.poses().len() >= 10);
//! ```

use std::cell::RefCell;
use std::fmt::Debug;
use std::io::{self, BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::rc::Rc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::driver::Interface;
use crate::{
    AnalogRemote, ButtonRemote, DialRemote, Error, TextReceiver, TextSeverity, TimeVal,
    TrackerPose, TrackerRemote,
};

/// A `vrpn_server` child process on a configuration of its own, on a free port of
/// 127.0.0.1's interfaces; killed (by its PID) when dropped.
pub struct ServerProcess {
    child: Child,
    port: u16,
    stderr: Arc<Mutex<String>>,
    dir: PathBuf,
}

static NEXT: AtomicUsize = AtomicUsize::new(0);

impl ServerProcess {
    /// Starts `exe` (a `vrpn_server`) on `cfg` (the text of a vrpn.cfg) at port 0, with
    /// `options` before the port, and reads the port it took from its first line.
    pub fn start_with(exe: &Path, cfg: &str, options: &[&str]) -> io::Result<ServerProcess> {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("vrpn-rig-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let path = dir.join("vrpn.cfg");
        std::fs::write(&path, cfg)?;
        let mut child = Command::new(exe)
            .arg("-f")
            .arg(&path)
            .args(options)
            .arg("0")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        let stderr = Arc::new(Mutex::new(String::new()));
        if let Some(mut err) = child.stderr.take() {
            let e = stderr.clone();
            std::thread::spawn(move || {
                let mut buf = [0u8; 4096];
                while let Ok(n) = err.read(&mut buf) {
                    if n == 0 {
                        break;
                    }
                    if let Ok(mut s) = e.lock() {
                        s.push_str(&String::from_utf8_lossy(&buf[..n]));
                    }
                }
            });
        }
        let Some(stdout) = child.stdout.take() else {
            return Err(io::Error::other("no standard output from the server"));
        };
        let mut out = BufReader::new(stdout);
        let mut line = String::new();
        out.read_line(&mut line)?;
        let port = line
            .split("on port ")
            .nth(1)
            .and_then(|s| s.split_whitespace().next())
            .and_then(|p| p.parse().ok());
        // Drain standard output so the server never blocks on a full pipe.
        std::thread::spawn(move || {
            let mut sink = Vec::new();
            let _ = out.read_to_end(&mut sink);
        });
        let mut server = ServerProcess {
            child,
            port: 0,
            stderr,
            dir,
        };
        match port {
            Some(p) => {
                server.port = p;
                Ok(server)
            }
            None => {
                // Give its error a moment to arrive, for the message.
                std::thread::sleep(Duration::from_millis(100));
                Err(io::Error::other(format!(
                    "the server did not start: {line:?}; it said: {}",
                    server.stderr()
                )))
            }
        }
    }

    /// [`start_with`](Self::start_with) without options.
    pub fn start(exe: &Path, cfg: &str) -> io::Result<ServerProcess> {
        ServerProcess::start_with(exe, cfg, &[])
    }

    /// The TCP/UDP port it serves on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// Its process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Everything it wrote to its standard error so far.
    pub fn stderr(&self) -> String {
        self.stderr.lock().map(|s| s.clone()).unwrap_or_default()
    }
}

impl Drop for ServerProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Where a [`Client`] reads: a server over TCP, or a connection in this process.
enum Source<'a> {
    Tcp(&'a str),
    Conn(&'a str, &'a crate::Connection),
}

/// One thing the client heard, in the order heard.
#[derive(Clone, Debug, PartialEq)]
pub enum Heard {
    /// A tracker pose.
    Pose(TrackerPose),
    /// A button changed.
    Button {
        /// Button index.
        button: usize,
        /// Pressed (true) or released.
        pressed: bool,
        /// The server's time stamp.
        time: TimeVal,
    },
    /// An analog report: every channel.
    Analog {
        /// The channels' values.
        channels: Vec<f64>,
        /// The server's time stamp.
        time: TimeVal,
    },
    /// A dial turned.
    Dial {
        /// Dial index.
        dial: usize,
        /// Revolutions since the previous report.
        change: f64,
        /// The server's time stamp.
        time: TimeVal,
    },
    /// A text message from the device.
    Text {
        /// Its severity.
        severity: TextSeverity,
        /// The text.
        text: String,
    },
}

/// A client of one device name over TCP only (no datagram can be lost on a busy machine):
/// a remote per interface asked for, plus the device's text messages, all recorded in one
/// log in the order they arrived. Pump it with [`pump_until`](Self::pump_until) or
/// [`wait_until`](Self::wait_until).
pub struct Client {
    log: Rc<RefCell<Vec<Heard>>>,
    pump: Vec<Box<dyn Fn() -> Result<(), Error>>>,
}

impl Client {
    /// Connects to `name` on the server at 127.0.0.1:`port`, reading `interfaces` and texts.
    pub fn connect(name: &str, port: u16, interfaces: &[Interface]) -> Result<Client, Error> {
        let at = format!("{name}@tcp://127.0.0.1:{port}");
        Client::build(&Source::Tcp(&at), interfaces)
    }

    /// Reads `name`'s `interfaces` and texts on `conn` itself (a loopback connection in a
    /// driver's virtual-line tests, where reports are delivered as they are sent: no pumping
    /// needed).
    pub fn on_connection(
        name: &str,
        conn: &crate::Connection,
        interfaces: &[Interface],
    ) -> Result<Client, Error> {
        Client::build(&Source::Conn(name, conn), interfaces)
    }

    fn build(source: &Source<'_>, interfaces: &[Interface]) -> Result<Client, Error> {
        let log: Rc<RefCell<Vec<Heard>>> = Rc::default();
        let mut pump: Vec<Box<dyn Fn() -> Result<(), Error>>> = Vec::new();
        for interface in interfaces {
            let l = log.clone();
            match interface {
                Interface::Tracker => {
                    let r = match source {
                        Source::Tcp(at) => TrackerRemote::new(at)?,
                        Source::Conn(name, conn) => TrackerRemote::on_connection(name, conn)?,
                    };
                    r.on_pose(move |p| l.borrow_mut().push(Heard::Pose(*p)));
                    pump.push(Box::new(move || r.mainloop()));
                }
                Interface::Button => {
                    let r = match source {
                        Source::Tcp(at) => ButtonRemote::new(at)?,
                        Source::Conn(name, conn) => ButtonRemote::on_connection(name, conn)?,
                    };
                    r.on_change(move |c| {
                        l.borrow_mut().push(Heard::Button {
                            button: c.button,
                            pressed: c.state.is_pressed(),
                            time: c.time,
                        })
                    });
                    pump.push(Box::new(move || r.mainloop()));
                }
                Interface::Analog => {
                    let r = match source {
                        Source::Tcp(at) => AnalogRemote::new(at)?,
                        Source::Conn(name, conn) => AnalogRemote::on_connection(name, conn)?,
                    };
                    r.on_report(move |a| {
                        l.borrow_mut().push(Heard::Analog {
                            channels: a.channel[..a.num_channel].to_vec(),
                            time: a.time,
                        })
                    });
                    pump.push(Box::new(move || r.mainloop()));
                }
                Interface::Dial => {
                    let r = match source {
                        Source::Tcp(at) => DialRemote::new(at)?,
                        Source::Conn(name, conn) => DialRemote::on_connection(name, conn)?,
                    };
                    r.on_update(move |d| {
                        l.borrow_mut().push(Heard::Dial {
                            dial: d.dial,
                            change: d.change,
                            time: d.time,
                        })
                    });
                    pump.push(Box::new(move || r.mainloop()));
                }
                _ => {
                    return Err(Error::Unsupported(
                        "the rig's client reads trackers, buttons, analogs and dials",
                    ))
                }
            }
        }
        let texts = match source {
            Source::Tcp(at) => TextReceiver::new(at)?,
            Source::Conn(name, conn) => TextReceiver::on_connection(name, conn)?,
        };
        let l = log.clone();
        texts.on_message(move |m| {
            l.borrow_mut().push(Heard::Text {
                severity: m.severity,
                text: m.text().to_owned(),
            })
        });
        pump.push(Box::new(move || texts.mainloop()));
        Ok(Client { log, pump })
    }

    /// Forgets everything heard so far.
    pub fn clear(&self) {
        self.log.borrow_mut().clear();
    }

    /// Everything heard so far, in order.
    pub fn heard(&self) -> Vec<Heard> {
        self.log.borrow().clone()
    }

    /// How many things were heard so far (an index to look from later).
    pub fn len(&self) -> usize {
        self.log.borrow().len()
    }

    /// True before anything was heard.
    pub fn is_empty(&self) -> bool {
        self.log.borrow().is_empty()
    }

    /// The poses heard, in order.
    pub fn poses(&self) -> Vec<TrackerPose> {
        self.poses_from(0)
    }

    /// The poses heard from log index `from` on.
    pub fn poses_from(&self, from: usize) -> Vec<TrackerPose> {
        let log = self.log.borrow();
        log[from.min(log.len())..]
            .iter()
            .filter_map(|h| match h {
                Heard::Pose(p) => Some(*p),
                _ => None,
            })
            .collect()
    }

    /// The texts heard from log index `from` on.
    pub fn texts_from(&self, from: usize) -> Vec<String> {
        let log = self.log.borrow();
        log[from.min(log.len())..]
            .iter()
            .filter_map(|h| match h {
                Heard::Text { text, .. } => Some(text.clone()),
                _ => None,
            })
            .collect()
    }

    /// The reports (everything but texts) heard from log index `from` on.
    pub fn reports_from(&self, from: usize) -> Vec<Heard> {
        let log = self.log.borrow();
        log[from.min(log.len())..]
            .iter()
            .filter(|h| !matches!(h, Heard::Text { .. }))
            .cloned()
            .collect()
    }

    /// Pumps the connection until `done` holds or `max` passes; returns whether it held.
    pub fn pump_until(&self, max: Duration, done: impl Fn(&Client) -> bool) -> bool {
        let start = Instant::now();
        while start.elapsed() < max {
            for p in &self.pump {
                // A connection problem shows as nothing heard; the caller's check says so.
                let _ = p();
            }
            if done(self) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        done(self)
    }

    /// [`pump_until`](Self::pump_until), panicking with what was heard and what the server
    /// said when `done` never holds.
    pub fn wait_until(
        &self,
        max: Duration,
        what: &str,
        server: &ServerProcess,
        done: impl Fn(&Client) -> bool,
    ) {
        if !self.pump_until(max, done) {
            let texts = self.texts_from(0);
            panic!(
                "{what}: not within {max:?}; {} reports heard; texts {texts:?}; the server said: \
                 {}",
                self.reports_from(0).len(),
                server.stderr()
            );
        }
    }

    /// Waits for a text containing `part`, heard at log index `from` or later.
    pub fn wait_text(&self, from: usize, part: &str, max: Duration, server: &ServerProcess) {
        self.wait_until(max, &format!("a text with {part:?}"), server, |c| {
            c.texts_from(from).iter().any(|t| t.contains(part))
        });
    }
}

/// Where `got` stands as one contiguous run in `sent` at or after index `after`: every start
/// index that fits (a device that starts its values over after a reset can put the same run
/// in its log twice).
pub fn runs_in<T: PartialEq>(got: &[T], sent: &[T], after: usize) -> Vec<usize> {
    (after..sent.len())
        .filter(|&i| {
            got.iter()
                .enumerate()
                .all(|(k, g)| sent.get(i + k) == Some(g))
        })
        .collect()
}

/// Where in `sent` (what the simulator logged) the records a client has not heard yet start:
/// just after the most recent place, among the first `logged` records, where the last values
/// the client heard (`heard`, up to four of them) stand in a row; `logged` when they stand
/// nowhere, 0 when nothing was heard.
///
/// Marking "what was logged when the client's log was marked" is not enough on a loaded
/// machine: a starved server can have many records on their way, and they arrive after the
/// mark.
pub fn resume_after<T: PartialEq>(heard: &[T], sent: &[T], logged: usize) -> usize {
    let logged = logged.min(sent.len());
    let tail = &heard[heard.len().saturating_sub(4)..];
    if tail.is_empty() {
        return 0;
    }
    (tail.len()..=logged)
        .rev()
        .find(|&end| sent[end - tail.len()..end] == *tail)
        .unwrap_or(logged)
}

/// Asserts that `got` (what the client received) is one contiguous run of `sent` (what the
/// simulator logged) at or after `after`, so nothing was lost, added, changed or reordered
/// (the client may have joined mid-stream, and the last records may still be on their way).
/// Returns the possible start indexes, the latest first: a device that starts its values over
/// (after a reset or a replug) logs the same run more than once, and the client's log ends near
/// the present, so the latest place is the one it heard (the one to check stamps against).
pub fn assert_run_of<T: PartialEq + Debug>(
    got: &[T],
    sent: &[T],
    after: usize,
    what: &str,
) -> Vec<usize> {
    assert!(!got.is_empty(), "{what}: nothing received");
    let runs = runs_in(got, sent, after);
    if runs.is_empty() {
        // Where the longest stretch that does match ends tells what went wrong.
        let (start, len) = (after..sent.len())
            .map(|i| {
                let n = got
                    .iter()
                    .zip(&sent[i..])
                    .take_while(|(g, s)| g == s)
                    .count();
                (i, n)
            })
            .max_by_key(|&(_, n)| n)
            .unwrap_or((after, 0));
        let around = |v: &[T], at: usize| -> String {
            let lo = at.saturating_sub(2).min(v.len());
            format!("{:?}", &v[lo..v.len().min(at + 3)])
        };
        panic!(
            "{what}: the {} values received are not a run of the {} sent from {after} (first \
             received {:?}; sent from there: {:?}); the longest match starts at sent[{start}] \
             and ends after {len} values: received around there {}, sent around there {}",
            got.len(),
            sent.len().saturating_sub(after),
            got[0],
            &sent[after.min(sent.len())..sent.len().min(after + 3)],
            around(got, len),
            around(sent, start + len),
        );
    }
    let mut runs = runs;
    runs.reverse();
    runs
}

/// Asserts that the report times in `stamps` are the arrivals of their records' first bytes,
/// against the moments the simulator wrote those bytes (`sent_at`, on the monotonic clock of
/// `t0`).
///
/// Reports stamped with the same time came from one read (a read takes everything that
/// arrived since the poll woke; what was waiting at the wake gets the wake time): each such
/// read counts once, with the lag of its first record. Over the reads, the median lag lies between −2 ms and
/// `max_lag` / 5, and at most one in ten (at least two allowed) exceeds `max_lag`: those
/// are the reader starved on a loaded machine (CI runs many servers at once), which then finds
/// a backlog. No report may be stamped more than 50 ms before its byte left. A stamp taken at
/// the end of a record, or when it was decoded, is late for every read and shows in the
/// median.
///
/// `sent_at` is when the byte was due on the line; the simulator's write can come later, so a
/// stamp is compared with a time at or before the byte's real arrival. (The serial layer
/// stamps bytes that came after the wake with the late read's time, never the wake's.)
pub fn assert_first_byte_stamps(
    stamps: &[TimeVal],
    sent_at: &[Instant],
    t0: crate::Now,
    max_lag: Duration,
    what: &str,
) {
    assert!(
        sent_at.len() >= stamps.len(),
        "{what}: more stamps than records"
    );
    let lags: Vec<f64> = stamps
        .iter()
        .zip(sent_at)
        .map(|(stamp, &at)| {
            let left = t0.wall.plus(at.saturating_duration_since(t0.mono));
            stamp.seconds_since(left)
        })
        .collect();
    for (i, lag) in lags.iter().enumerate() {
        assert!(
            *lag >= -0.05,
            "{what}: report {i} stamped {:.6} s before its first byte left the simulator",
            -lag
        );
    }
    // One lag per read: the first report of each run with the same stamp.
    let reads: Vec<(usize, f64)> = lags
        .iter()
        .copied()
        .enumerate()
        .filter(|&(i, _)| i == 0 || stamps[i] != stamps[i - 1])
        .collect();
    let late: Vec<(usize, f64)> = reads
        .iter()
        .copied()
        .filter(|&(_, lag)| lag >= max_lag.as_secs_f64())
        .collect();
    assert!(
        late.len() <= (reads.len() / 10).max(2),
        "{what}: {} of {} reads stamped more than {max_lag:?} after their first byte left the \
         simulator (report, lag in s): {late:?}",
        late.len(),
        reads.len()
    );
    let mut lags: Vec<f64> = reads.iter().map(|&(_, lag)| lag).collect();
    lags.sort_by(f64::total_cmp);
    if let Some(&median) = lags.get(lags.len() / 2) {
        assert!(
            (-0.002..max_lag.as_secs_f64() / 5.0).contains(&median),
            "{what}: the median report is stamped {median:.6} s after its first byte left"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::{assert_first_byte_stamps, resume_after};
    use crate::{Now, TimeVal};
    use std::time::{Duration, Instant};

    /// 100 records 10 ms apart from `t0`, and stamps `lag(i)` seconds after each.
    fn stamps(t0: Now, lag: impl Fn(usize) -> f64) -> (Vec<TimeVal>, Vec<Instant>) {
        (0..100)
            .map(|i| {
                let at = t0.mono + Duration::from_millis(10 * i as u64);
                let left = t0.wall.plus(at - t0.mono);
                (left.plus_secs(lag(i)), at)
            })
            .unzip()
    }

    fn check(lag: impl Fn(usize) -> f64) -> bool {
        let t0 = Now::read();
        let (s, at) = stamps(t0, lag);
        std::panic::catch_unwind(|| {
            assert_first_byte_stamps(&s, &at, t0, Duration::from_millis(250), "test")
        })
        .is_ok()
    }

    #[test]
    fn records_still_on_their_way_are_found_after_the_last_heard() {
        let sent = [1, 2, 3, 1, 2, 3, 4, 5, 6];
        assert_eq!(resume_after(&[1, 2], &sent, 9), 5);
        assert_eq!(resume_after(&[3, 1, 2], &sent, 9), 5);
        assert_eq!(resume_after(&[1, 2], &sent, 4), 2);
        assert_eq!(resume_after(&[7], &sent, 6), 6);
        assert_eq!(resume_after::<i32>(&[], &sent, 6), 0);
    }

    #[test]
    fn first_byte_stamps_pass_and_late_or_early_ones_fail() {
        assert!(check(|_| 0.0002));
        // A starved reader: a few reports late by most of a second.
        assert!(check(|i| if i % 40 == 7 { 0.74 } else { 0.0002 }));
        // A reader starved for 0.7 s finds 40 records and stamps them all with its wake time.
        let t0 = Now::read();
        let (mut s, at) = stamps(t0, |_| 0.0002);
        let woke = s[30].plus_secs(0.7);
        s[30..70].iter_mut().for_each(|t| *t = woke);
        assert_first_byte_stamps(&s, &at, t0, Duration::from_millis(250), "starved");
        // Too many late ones, every one late (stamped at the end of a long record), or one
        // stamped well before its byte left.
        assert!(!check(|i| if i % 5 == 2 { 0.74 } else { 0.0002 }));
        assert!(!check(|_| 0.06));
        assert!(!check(|i| if i == 50 { -0.2 } else { 0.0002 }));
    }
}
