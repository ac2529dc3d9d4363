//! What the monitor knows about each device: the latest reports of every kind a device may
//! offer (tracker, button, analog, dial, text), counts and rates, and its connection's state,
//! turned into the JSON snapshot the page draws.

use std::cell::RefCell;
use std::collections::{BTreeMap, VecDeque};
use std::rc::Rc;
use std::time::Instant;

use serde_json::{json, Value};
use vrpn::{
    AnalogRemote, ButtonRemote, Connection, ConnectionEvent, DialRemote, Error, TextReceiver,
    TimeVal, TrackerRemote,
};

/// Text messages kept per device.
const TEXTS_KEPT: usize = 8;
/// How often rates are worked out again.
const RATE_WINDOW: f64 = 0.5;

/// Reports per second of one stream, over windows of [`RATE_WINDOW`].
#[derive(Default)]
struct Rate {
    count: u64,
    mark: Option<(Instant, u64)>,
    hz: f64,
}

impl Rate {
    fn tick(&mut self) {
        self.count += 1;
    }

    /// Updates the rate at `now` (at most once per window).
    fn update(&mut self, now: Instant) {
        match self.mark {
            None => self.mark = Some((now, self.count)),
            Some((t, n)) => {
                let dt = now.duration_since(t).as_secs_f64();
                if dt >= RATE_WINDOW {
                    self.hz = (self.count - n) as f64 / dt;
                    self.mark = Some((now, self.count));
                }
            }
        }
    }
}

/// The latest pose of one sensor.
#[derive(Default)]
struct Sensor {
    pos: [f64; 3],
    quat: [f64; 4],
    /// The report's time, translated to our clock when clock synchronisation is in effect.
    time: TimeVal,
    arrival: TimeVal,
    rate: Rate,
}

/// Everything one device reported, written by the remotes' callbacks.
#[derive(Default)]
struct Reports {
    sensors: BTreeMap<usize, Sensor>,
    buttons: Vec<bool>,
    presses: Vec<u64>,
    button_reports: u64,
    channels: Vec<f64>,
    analog_rate: Rate,
    dials: Vec<f64>,
    dial_reports: u64,
    texts: VecDeque<(f64, &'static str, String)>,
}

impl Reports {
    fn button(&mut self, i: usize, pressed: bool) {
        if self.buttons.len() <= i {
            self.buttons.resize(i + 1, false);
            self.presses.resize(i + 1, 0);
        }
        if pressed && !self.buttons[i] {
            self.presses[i] += 1;
        }
        self.buttons[i] = pressed;
        self.button_reports += 1;
    }

    fn text(&mut self, time: TimeVal, severity: &'static str, text: String) {
        if self.texts.len() == TEXTS_KEPT {
            self.texts.pop_front();
        }
        self.texts.push_back((time.as_secs_f64(), severity, text));
    }
}

/// One connection's state as the page shows it.
#[derive(Default)]
struct Link {
    connections: u64,
}

/// One monitored device: a remote of every kind on its connection, and what they reported.
pub struct Device {
    name: String,
    location: String,
    conn: Connection,
    reports: Rc<RefCell<Reports>>,
    link: Rc<RefCell<Link>>,
    // Kept alive: their callbacks fill `reports`.
    _tracker: TrackerRemote,
    _button: ButtonRemote,
    _analog: AnalogRemote,
    _dial: DialRemote,
    _text: TextReceiver,
}

impl Device {
    /// Opens `name` (`DEVICE@HOST[:PORT]`) as every kind of remote at once: the monitor does
    /// not know which interfaces the device has, and a server sends each kind only to remotes
    /// of that kind.
    pub fn open(name: &str) -> Result<Device, Error> {
        let tracker = TrackerRemote::new(name)?;
        let button = ButtonRemote::new(name)?;
        let analog = AnalogRemote::new(name)?;
        let dial = DialRemote::new(name)?;
        let text = TextReceiver::new(name)?;
        let conn = tracker.connection().clone();
        let reports = Rc::new(RefCell::new(Reports::default()));
        let link = Rc::new(RefCell::new(Link::default()));

        let r = reports.clone();
        tracker.on_pose(move |p| {
            let mut r = r.borrow_mut();
            let s = r.sensors.entry(p.sensor).or_default();
            s.pos = [p.pos.x, p.pos.y, p.pos.z];
            let q = p.quat.quaternion();
            s.quat = [q.i, q.j, q.k, q.w];
            s.time = p.time;
            s.arrival = p.arrival;
            s.rate.tick();
        });
        let r = reports.clone();
        button.on_change(move |c| r.borrow_mut().button(c.button, c.state.is_pressed()));
        let r = reports.clone();
        button.on_states(move |s| {
            let mut r = r.borrow_mut();
            for (i, st) in s.states[..s.num_buttons].iter().enumerate() {
                let pressed = st.is_pressed();
                if r.buttons.len() <= i || r.buttons[i] != pressed {
                    r.button(i, pressed);
                }
            }
        });
        let r = reports.clone();
        analog.on_report(move |a| {
            let mut r = r.borrow_mut();
            r.channels.clear();
            r.channels.extend_from_slice(&a.channel[..a.num_channel]);
            r.analog_rate.tick();
        });
        let r = reports.clone();
        dial.on_update(move |d| {
            let mut r = r.borrow_mut();
            if r.dials.len() <= d.dial {
                r.dials.resize(d.dial + 1, 0.0);
            }
            r.dials[d.dial] += d.change;
            r.dial_reports += 1;
        });
        let r = reports.clone();
        text.on_message(move |m| {
            let severity = match m.severity {
                vrpn::TextSeverity::Normal => "normal",
                vrpn::TextSeverity::Warning => "warning",
                _ => "error",
            };
            r.borrow_mut().text(m.time, severity, m.text().to_string());
        });
        let l = link.clone();
        conn.on_event(ConnectionEvent::GotConnection, move || {
            l.borrow_mut().connections += 1
        });
        let r = reports.clone();
        conn.on_notice(move |n| {
            let severity = match n.severity {
                vrpn::Severity::Info => "notice",
                vrpn::Severity::Warning => "warning",
                vrpn::Severity::Error => "error",
            };
            r.borrow_mut()
                .text(TimeVal::now(), severity, n.text.clone());
        });
        let (device, location) = name.split_once('@').unwrap_or((name, ""));
        Ok(Device {
            name: device.to_string(),
            location: location.to_string(),
            conn,
            reports,
            link,
            _tracker: tracker,
            _button: button,
            _analog: analog,
            _dial: dial,
            _text: text,
        })
    }

    /// The device name (before the `@`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The connection it reports on (shared by the devices at one location).
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// The device's state as JSON, at wall time `now` and monotonic `mono`.
    pub fn snapshot(&self, now: TimeVal, mono: Instant) -> Value {
        let mut r = self.reports.borrow_mut();
        let synced = self.conn.clock_estimate();
        let now_s = now.as_secs_f64();
        let sensors: Vec<Value> = r
            .sensors
            .iter_mut()
            .map(|(id, s)| {
                s.rate.update(mono);
                let arrival = s.arrival.as_secs_f64();
                json!({
                    "id": id,
                    "pos": s.pos,
                    "quat": s.quat,
                    "count": s.rate.count,
                    "rate": s.rate.hz,
                    "age": now_s - arrival,
                    // Only meaningful when the report's time is on our clock.
                    "latency": synced.map(|_| arrival - s.time.as_secs_f64()),
                })
            })
            .collect();
        r.analog_rate.update(mono);
        let link = self.link.borrow();
        json!({
            "name": self.name,
            "location": self.location,
            "state": match self.conn.state() {
                vrpn::ConnectionState::Connecting => "connecting",
                vrpn::ConnectionState::Connected => "connected",
                vrpn::ConnectionState::Reconnecting => "reconnecting",
                vrpn::ConnectionState::Listening => "listening",
                _ => "unknown",
            },
            "reconnects": link.connections.saturating_sub(1),
            "clock": synced.map(|e| json!({"offset": e.offset, "uncertainty": e.uncertainty})),
            "sensors": sensors,
            "buttons": if r.button_reports > 0 {
                json!({"states": r.buttons, "presses": r.presses})
            } else {
                Value::Null
            },
            "analog": if r.analog_rate.count > 0 {
                json!({"channels": r.channels, "count": r.analog_rate.count, "rate": r.analog_rate.hz})
            } else {
                Value::Null
            },
            "dials": if r.dial_reports > 0 {
                json!({"totals": r.dials, "count": r.dial_reports})
            } else {
                Value::Null
            },
            "texts": r.texts.iter().map(|(t, sev, text)| json!({"time": t, "severity": sev, "text": text})).collect::<Vec<_>>(),
        })
    }
}
