//! A unit-test rig for a serial driver that reports an Analog: the driver on a
//! [`VirtualLine`] to its simulator, on an in-process connection with an Analog remote that
//! keeps every report (channels and stamp) and a handler that keeps the device's texts; and
//! the check that reports are the simulator's records, exact and stamped with their first
//! bytes. Shared by the drivers' `tests.rs` (the 5DT gloves, the Streaming Arduino).

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::serial::SerialDriver;
use crate::sim::{DeviceModel, VirtualLine};
use crate::{AnalogRemote, Connection, Now, SenderFilter, TimeVal};

/// The reports heard: channels and stamp.
pub(crate) type Heard = Rc<RefCell<Vec<(Vec<f64>, TimeVal)>>>;

/// A simulator's log: each record's channels and the moment its first byte left.
pub(crate) type Log<M> = fn(&M) -> Vec<(Vec<f64>, Instant)>;

/// The rig. See the module documentation.
pub(crate) struct AnalogLine<D: SerialDriver, M: DeviceModel> {
    pub line: VirtualLine<D, M>,
    /// When the line started (a fixed wall clock).
    pub start: Now,
    pub heard: Heard,
    pub texts: Rc<RefCell<Vec<String>>>,
    log: Log<M>,
    _remote: AnalogRemote,
    _conn: Connection,
}

impl<D: SerialDriver, M: DeviceModel> AnalogLine<D, M> {
    /// Keeps texts off the test output, makes the driver with `driver` on a loopback
    /// connection, listens to `name`'s Analog and texts there, and joins the driver to
    /// `device` (random choices seeded with `seed`); `log` reads the simulator's log.
    pub fn new(
        name: &str,
        driver: impl FnOnce(&Connection) -> D,
        device: M,
        seed: u64,
        log: Log<M>,
    ) -> Self {
        set_print_threshold(TextSeverity::Other(u32::MAX));
        let conn = Connection::new_loopback();
        let driver = driver(&conn);
        let heard: Heard = Rc::default();
        let remote = AnalogRemote::on_connection(name, &conn).unwrap();
        let h = heard.clone();
        remote.on_report(move |a| {
            h.borrow_mut()
                .push((a.channel[..a.num_channel].to_vec(), a.time))
        });
        let texts: Rc<RefCell<Vec<String>>> = Rc::default();
        let sender = conn.register_sender(name).unwrap();
        let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
        let t = texts.clone();
        conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
            if let Some((_, _, text)) = decode_text(m.payload) {
                t.borrow_mut().push(text.to_owned());
            }
        });
        let start = Now {
            mono: Instant::now(),
            wall: TimeVal::new(1_700_000_000, 0),
        };
        AnalogLine {
            line: VirtualLine::new(driver, device, start, seed),
            start,
            heard,
            texts,
            log,
            _remote: remote,
            _conn: conn,
        }
    }

    /// Runs the line until `n` reports were heard; fails (with the texts) after `max`.
    pub fn run_until_reports(&mut self, n: usize, max: Duration) {
        let h = self.heard.clone();
        assert!(
            self.line.run_until(max, |_| h.borrow().len() >= n),
            "{} of {n} reports; texts {:?}",
            self.heard.borrow().len(),
            self.texts.borrow()
        );
    }

    /// Reports from `from` on are a contiguous run of the records logged from `after` on,
    /// each stamped with its first byte (values only after a slow read, whose records all
    /// carry its wake time). Returns the index of the first record matched.
    pub fn check(&self, from: usize, after: usize) -> usize {
        let heard = self.heard.borrow();
        let got = &heard[from..];
        let sent = (self.log)(&self.line.device);
        let start = (after..sent.len())
            .find(|&i| sent[i].0[..] == got[0].0[..])
            .unwrap_or_else(|| panic!("first report {:?} never sent", got[0]));
        for (i, (channels, time)) in got.iter().enumerate() {
            let (values, first_byte) = &sent[start + i];
            assert_eq!(channels[..], values[..], "report {i}");
            if !self.line.read_lag.is_zero() {
                continue;
            }
            let want = self.start.wall.plus(*first_byte - self.start.mono);
            let late = time.seconds_since(want);
            assert!((0.0..0.002).contains(&late), "report {i}: {late} s late");
        }
        start
    }

    /// Whether a text containing `part` was heard.
    pub fn has_text(&self, part: &str) -> bool {
        self.texts.borrow().iter().any(|t| t.contains(part))
    }
}
