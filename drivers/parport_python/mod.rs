//! The UNC "Python" button box (five buttons on a parallel port's status lines, also used
//! for the HiBall's buttons): its `vrpn.cfg` line ([`config`]), the port it reads
//! ([`source`]: Linux `ppdev`, no port I/O privileges), the device, and a fake port for tests
//! (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Button_Python NAME PORT [HEX_ADDRESS]
//! ```
//!
//! `PORT` counts from 1: port 1 is `/dev/parport0`. `HEX_ADDRESS` (an I/O base address, such
//! as `378`) is read and ignored, as C++ ignores it on Linux (it is for Windows' direct port
//! access).
//!
//! # What is sent
//!
//! `NAME` is a Button with 5 buttons, from the status register: 0 SELECT low, 1 BUSY high
//! (the register's bit, which the port inverts), 2 PAPER-OUT low, 3 ERROR low, 4 ACK low. The
//! register is read [`READS_PER_SAMPLE`] times every [`SAMPLE_PERIOD`]; a sample whose reads
//! differ is dropped (the buttons are bouncing), as C++ does. Each change sends a
//! `vrpn_Button Change` (toggle modes applied, as C++), stamped with the sample's time.
//!
//! # Supervision
//!
//! A port that cannot be opened or claimed sends an error text once (`vrpn_Button_Python:
//! cannot open PATH: …`) and is tried again every second; a read that fails sends
//! `vrpn_Button_Python: reading PATH failed: …; reopening` and the port is reopened; when it
//! opens again, `vrpn_Button_Python: PATH is open again`. Nothing is reported meanwhile (a
//! reset never invents data).
//!
//! **The `ppdev` path has not been exercised against a real parallel port**: the tests stand
//! in for it with a fake port that answers the reads, and check only that the ioctls are
//! refused by files that are no parallel port.
//!
//! # Differences from C++ VRPN
//!
//! * C++ on Linux opens `/dev/lpN` and uses the printer driver's `LPGETSTATUS`; this driver
//!   uses `ppdev` (`/dev/parportN`, `PPCLAIM`, `PPRSTATUS`), which reads the same register
//!   without a printer driver in the way, and writes 3 to the data register after claiming the
//!   port (what C++ does on Windows to power the box; C++ on Linux could not).
//! * C++ samples on every pass of its loop (as fast as the loop spins); here every 5 ms,
//!   which lets the server sleep.
//! * A port that fails is reopened; C++ gives up (`Failure`) until restarted.

pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
pub mod source;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::source::StatusSource;
use crate::devices::text::TextSeverity;
use crate::devices::ServerDevice;
use crate::driver::text::with_text;
use crate::driver::{DeviceStatus, Driver, OpenFailure, StatusSink};
use crate::time::Now;
use crate::{ButtonServer, Connection, Error};

pub use self::config::Python;

/// The registry entry: `vrpn_Button_Python`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Button_Python"],
    parse: config::parse,
    hints: &[],
};

/// Buttons on the box.
pub const BUTTONS: usize = 5;
/// Time between samples.
pub const SAMPLE_PERIOD: Duration = Duration::from_millis(5);
/// Reads per sample that must agree (C++'s debounce count).
pub const READS_PER_SAMPLE: usize = 30;
/// Time between attempts to open a port that failed.
pub const REOPEN_INTERVAL: Duration = Duration::from_secs(1);

const ERROR: u8 = 1 << 3;
const SELECT: u8 = 1 << 4;
const PAPER_OUT: u8 = 1 << 5;
const ACK: u8 = 1 << 6;
const BUSY: u8 = 1 << 7;
/// The status bits that carry buttons.
pub const STATUS_MASK: u8 = ERROR | SELECT | PAPER_OUT | ACK | BUSY;

/// The buttons a status register value says are pressed.
pub fn buttons(status: u8) -> [bool; BUTTONS] {
    [
        status & SELECT == 0,
        status & BUSY != 0,
        status & PAPER_OUT == 0,
        status & ERROR == 0,
        status & ACK == 0,
    ]
}

/// The port's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Port {
    /// Closed; the next attempt to open it at this time (`None`: at once).
    Closed(Option<Instant>),
    /// Open; the next sample at this time.
    Open(Instant),
}

/// Counts, for tests and diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Samples whose reads agreed.
    pub samples: u64,
    /// Samples dropped because their reads differed.
    pub bouncing: u64,
    /// Times the port was opened.
    pub opens: u64,
}

/// The box on a port: a device the server loop runs. See the module documentation.
pub struct PythonButtons<S: StatusSource> {
    name: String,
    source: S,
    buttons: ButtonServer,
    port: Port,
    /// The problem last reported, while it lasts (a failed open is told once).
    failing: bool,
    stats: Stats,
    status: Option<StatusSink>,
}

impl<S: StatusSource> PythonButtons<S> {
    /// The box `name` on `source`, its buttons served on `conn`. The port opens at the first
    /// pass.
    pub fn new(name: &str, source: S, conn: &Connection) -> Result<PythonButtons<S>, Error> {
        Ok(PythonButtons {
            name: name.to_owned(),
            source,
            buttons: ButtonServer::new(name, conn, BUTTONS)?,
            port: Port::Closed(None),
            failing: false,
            stats: Stats::default(),
            status: None,
        })
    }

    /// Also tells `sink` about the port's state changes (for the program to show them).
    pub fn report_status_to(&mut self, sink: StatusSink) {
        self.status = Some(sink);
    }

    fn tell(&self, status: DeviceStatus) {
        if let Some(sink) = &self.status {
            sink(&self.name, &status);
        }
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// The counts so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The port source.
    pub fn source(&self) -> &S {
        &self.source
    }

    fn say(&self, severity: TextSeverity, args: std::fmt::Arguments<'_>) {
        // A failed send is the connection's business (it reports and drops the peer).
        with_text(args, |t| {
            let _ = self.buttons.send_text(severity, 0, t);
        });
    }

    fn open(&mut self, now: Now) {
        match self.source.open() {
            Ok(()) => {
                self.stats.opens += 1;
                if self.failing {
                    self.failing = false;
                    self.say(
                        TextSeverity::Normal,
                        format_args!("vrpn_Button_Python: {} is open again", self.source.path()),
                    );
                    self.tell(DeviceStatus::Opened {
                        port: self.source.path().to_owned(),
                    });
                }
                self.port = Port::Open(now.mono);
            }
            Err(e) => {
                if !self.failing {
                    self.failing = true;
                    self.say(
                        TextSeverity::Error,
                        format_args!(
                            "vrpn_Button_Python: cannot open {}: {e}",
                            self.source.path()
                        ),
                    );
                    let reason = match e.kind() {
                        std::io::ErrorKind::PermissionDenied => OpenFailure::Other(
                            "permission denied (parallel ports belong to the 'lp' group: add \
                             the user running the server with 'sudo usermod -aG lp USER', then \
                             log in again)"
                                .to_owned(),
                        ),
                        _ => OpenFailure::from_io(&e),
                    };
                    self.tell(DeviceStatus::CannotOpen {
                        port: self.source.path().to_owned(),
                        reason,
                    });
                }
                self.port = Port::Closed(Some(now.mono + REOPEN_INTERVAL));
            }
        }
    }

    fn sample(&mut self, now: Now) {
        let mut first = None;
        let mut agree = true;
        for _ in 0..READS_PER_SAMPLE {
            match self.source.read_status() {
                Ok(s) => {
                    let s = s & STATUS_MASK;
                    agree &= first.map_or(true, |f| f == s);
                    first.get_or_insert(s);
                }
                Err(e) => {
                    self.failing = true;
                    self.say(
                        TextSeverity::Error,
                        format_args!(
                            "vrpn_Button_Python: reading {} failed: {e}; reopening",
                            self.source.path()
                        ),
                    );
                    self.tell(DeviceStatus::Lost {
                        port: self.source.path().to_owned(),
                        reason: e.to_string(),
                    });
                    self.source.close();
                    self.port = Port::Closed(Some(now.mono + REOPEN_INTERVAL));
                    return;
                }
            }
        }
        self.port = Port::Open(now.mono + SAMPLE_PERIOD);
        let Some(status) = first.filter(|_| agree) else {
            self.stats.bouncing += 1;
            return;
        };
        self.stats.samples += 1;
        for (i, pressed) in buttons(status).into_iter().enumerate() {
            self.buttons.set_button(i, pressed);
        }
        self.buttons.set_timestamp(now.wall);
        let _ = self.buttons.report_changes();
    }
}

impl<S: StatusSource> ServerDevice for PythonButtons<S> {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        match self.port {
            Port::Closed(at) if at.map_or(true, |t| now.mono >= t) => self.open(now),
            Port::Open(at) if now.mono >= at => self.sample(now),
            _ => {}
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        match self.port {
            Port::Closed(at) => at,
            Port::Open(at) => Some(at),
        }
    }
}
