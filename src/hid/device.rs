//! A driver on its hidraw or evdev nodes, as a device the server loop runs: the nodes are
//! found in sysfs, opened non-blocking and wait in the server's reactor; each report goes to
//! the driver stamped with the time the poll woke for it; a device that is absent is waited
//! for, and one that goes away is reported and picked up again when it returns — all driven
//! by the hot-plug watcher, never by looking at sysfs in a loop.

use std::cell::RefCell;
use std::io;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::driver::{HidDriver, HidMatch, HidOp, HidOps, NodeInfo, NodeKind};
use super::hotplug::Hotplug;
use super::input_event::{EventSource, EVENT_LEN};
use super::source::ReportSource;
use super::sysfs::{self, DeviceTree};
use crate::connection::Connection;
use crate::devices::base;
use crate::devices::text::TextSeverity;
use crate::devices::ServerDevice;
use crate::dispatch::SenderId;
use crate::driver::registry::BuildContext;
use crate::driver::status::{DeviceStatus, OpenFailure, StatusSink};
use crate::net::Reactor;
use crate::time::Now;

/// Largest report read (USB full-speed interrupt reports are at most 64 bytes, high-speed
/// 1024; hidraw's own limit is 4096).
pub const MAX_REPORT: usize = 4096;
/// After a node appears, an open that fails (udev may not have set its permissions yet) is
/// retried this often…
const EARLY_RETRY: Duration = Duration::from_millis(250);
/// …for this long; then only this often.
const EARLY_WINDOW: Duration = Duration::from_secs(3);
const LATE_RETRY: Duration = Duration::from_secs(5);
/// Without a hot-plug watcher (a sandbox without netlink), how often sysfs is looked at.
const RESCAN_WITHOUT_WATCHER: Duration = Duration::from_secs(1);
/// Records read from an evdev node per read call.
const EVENTS_PER_READ: usize = 64;

enum Watch {
    NotOpened,
    Open(Hotplug),
    Failed(String),
}

struct HubInner {
    tree: DeviceTree,
    reactor: Option<Reactor>,
    watch: RefCell<Watch>,
    /// Nodes open by a device of this hub: two lines for the same product take two devices.
    claims: RefCell<Vec<PathBuf>>,
}

/// What the HID and evdev devices of one process share: the device tree, the hot-plug
/// watcher (opened when a device first asks) and which nodes are taken. Clones share it.
#[derive(Clone)]
pub struct DeviceHub {
    inner: Rc<HubInner>,
}

impl std::fmt::Debug for DeviceHub {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DeviceHub")
            .field("tree", &self.inner.tree)
            .finish()
    }
}

impl DeviceHub {
    /// A hub over `tree` whose sockets wait in `reactor` (without one, devices look at their
    /// nodes on every pass).
    pub fn new(tree: DeviceTree, reactor: Option<&Reactor>) -> DeviceHub {
        DeviceHub {
            inner: Rc::new(HubInner {
                tree,
                reactor: reactor.cloned(),
                watch: RefCell::new(Watch::NotOpened),
                claims: RefCell::new(Vec::new()),
            }),
        }
    }

    /// The device tree.
    pub fn tree(&self) -> &DeviceTree {
        &self.inner.tree
    }

    /// The hot-plug generation (see [`Hotplug::generation`]); `None` when no watcher could
    /// be opened.
    pub fn generation(&self) -> Option<u64> {
        let mut w = self.inner.watch.borrow_mut();
        if matches!(*w, Watch::NotOpened) {
            *w = match Hotplug::open(&self.inner.tree, self.inner.reactor.as_ref()) {
                Ok(h) => Watch::Open(h),
                Err(e) => Watch::Failed(e.to_string()),
            };
        }
        match &*w {
            Watch::Open(h) => Some(h.generation()),
            _ => None,
        }
    }

    /// Why hot-plug events are not heard, if they are not.
    pub fn watcher_problem(&self) -> Option<String> {
        match &*self.inner.watch.borrow() {
            Watch::Failed(e) => Some(e.clone()),
            _ => None,
        }
    }

    /// The nodes of `kind` sysfs knows now.
    pub fn enumerate(&self, kind: NodeKind) -> Vec<NodeInfo> {
        match kind {
            NodeKind::Hidraw => sysfs::enumerate_hidraw(&self.inner.tree)
                .into_iter()
                .map(NodeInfo::Hid)
                .collect(),
            NodeKind::Evdev => sysfs::enumerate_input(&self.inner.tree)
                .into_iter()
                .map(NodeInfo::Input)
                .collect(),
        }
    }

    fn claimed(&self, p: &std::path::Path) -> bool {
        self.inner.claims.borrow().iter().any(|c| c == p)
    }

    fn claim(&self, p: PathBuf) {
        self.inner.claims.borrow_mut().push(p);
    }

    fn release(&self, p: &std::path::Path) {
        self.inner.claims.borrow_mut().retain(|c| c != p);
    }
}

enum Source {
    Report(ReportSource),
    Events(EventSource),
}

impl Source {
    fn fd(&self) -> std::os::fd::RawFd {
        match self {
            Source::Report(s) => s.fd(),
            Source::Events(s) => s.fd(),
        }
    }
}

struct OpenNode {
    info: Option<NodeInfo>,
    path: PathBuf,
    source: Source,
    token: Option<mio::Token>,
}

/// A driver and its nodes. See the module documentation.
pub struct HidDevice<D: HidDriver> {
    driver: D,
    name: String,
    conn: Connection,
    sender: Option<SenderId>,
    hub: DeviceHub,
    wants: Vec<HidMatch>,
    nodes: Vec<OpenNode>,
    /// The hot-plug generation last looked at (`None`: never looked).
    seen: Option<u64>,
    /// When to look again without a hot-plug event.
    look_at: Option<Instant>,
    /// When the nodes were last seen to appear (for the early retries).
    appeared: Option<Instant>,
    said_waiting: bool,
    was_lost: bool,
    last_problem: Option<String>,
    opens: u64,
    reports: u64,
    ops: HidOps,
    buf: Box<[u8; MAX_REPORT]>,
    status: Option<StatusSink>,
    /// The last pass's time (for the shutdown's feature answers).
    last_now: Option<Now>,
}

/// `driver` as a running device of the server `cx` builds for: its nodes found through the
/// context's device hub, its state changes told to the program.
pub fn serve<D: HidDriver + 'static>(driver: D, cx: &BuildContext<'_>) -> Box<dyn ServerDevice> {
    let mut device = HidDevice::new(driver, cx.hub(), cx.conn());
    if let Some(sink) = cx.status() {
        device.report_status_to(sink.clone());
    }
    Box::new(device)
}

impl<D: HidDriver> HidDevice<D> {
    /// Runs `driver` on the nodes it asks for, found through `hub`, reporting problems as
    /// texts from the driver's device on `conn` (and to the program, with
    /// [`report_status_to`](Self::report_status_to)).
    pub fn new(driver: D, hub: &DeviceHub, conn: &Connection) -> HidDevice<D> {
        let name = driver.name().to_string();
        let sender = base::register_sender(conn, &name).ok();
        HidDevice {
            wants: driver.interfaces(),
            driver,
            name,
            conn: conn.clone(),
            sender,
            hub: hub.clone(),
            nodes: Vec::new(),
            seen: None,
            look_at: None,
            appeared: None,
            said_waiting: false,
            was_lost: false,
            last_problem: None,
            opens: 0,
            reports: 0,
            ops: HidOps::new(),
            buf: Box::new([0; MAX_REPORT]),
            status: None,
            last_now: None,
        }
    }

    /// Also tells `sink` when the device is waited for, opened, cannot be opened or lost.
    pub fn report_status_to(&mut self, sink: StatusSink) {
        self.status = Some(sink);
    }

    fn tell(&self, status: DeviceStatus) {
        if let Some(sink) = &self.status {
            sink(&self.name, &status);
        }
    }

    /// The driver.
    pub fn driver(&self) -> &D {
        &self.driver
    }

    /// The driver, to change it.
    pub fn driver_mut(&mut self) -> &mut D {
        &mut self.driver
    }

    /// True while every node is open.
    pub fn is_open(&self) -> bool {
        !self.nodes.is_empty()
    }

    /// Times the device was opened.
    pub fn opens(&self) -> u64 {
        self.opens
    }

    /// Reports (or evdev records) read since construction.
    pub fn reports(&self) -> u64 {
        self.reports
    }

    /// The open nodes' device files.
    pub fn paths(&self) -> Vec<PathBuf> {
        self.nodes.iter().map(|n| n.path.clone()).collect()
    }

    /// What the device waits for, for messages.
    pub fn describe(&self) -> String {
        self.wants
            .iter()
            .map(HidMatch::describe)
            .collect::<Vec<_>>()
            .join(" and ")
    }

    fn text(&self, severity: TextSeverity, text: &str) {
        if let Some(sender) = self.sender {
            let _ = self.conn.send_text(sender, severity, 0, text);
        }
    }

    /// A problem, said once until it changes.
    fn problem(&mut self, severity: TextSeverity, text: String) {
        if self.last_problem.as_deref() != Some(text.as_str()) {
            self.text(severity, &text);
            self.last_problem = Some(text);
        }
    }

    /// Picks a node for every interface: the first that matches and no other device holds.
    fn find(&self) -> Option<Vec<(Option<NodeInfo>, PathBuf)>> {
        let mut lists: [Option<Vec<NodeInfo>>; 2] = [None, None];
        let mut chosen: Vec<(Option<NodeInfo>, PathBuf)> = Vec::with_capacity(self.wants.len());
        let dev = self.hub.tree().dev().to_path_buf();
        for want in &self.wants {
            let slot = match want.kind {
                NodeKind::Hidraw => 0,
                NodeKind::Evdev => 1,
            };
            let list = lists[slot].get_or_insert_with(|| self.hub.enumerate(want.kind));
            let free = |n: &NodeInfo| {
                !self.hub.claimed(n.devnode()) && !chosen.iter().any(|(_, p)| p == n.devnode())
            };
            let found = if want.nth > 0 {
                list.iter()
                    .filter(|n| want.accepts(n, &dev))
                    .nth(want.nth)
                    .filter(|n| free(n))
            } else {
                list.iter().find(|n| want.accepts(n, &dev) && free(n))
            };
            match (found, want.path()) {
                (Some(n), _) => chosen.push((Some(n.clone()), n.devnode().to_path_buf())),
                // A configured file sysfs does not know (a pipe standing in for a node).
                (None, Some(p)) => {
                    let p = self.hub.tree().node_path(p);
                    if !p.exists() || self.hub.claimed(&p) {
                        return None;
                    }
                    chosen.push((None, p));
                }
                (None, None) => return None,
            }
        }
        Some(chosen)
    }

    fn open_one(
        &self,
        kind: NodeKind,
        info: Option<NodeInfo>,
        path: PathBuf,
    ) -> io::Result<OpenNode> {
        let source = match kind {
            NodeKind::Hidraw => Source::Report(ReportSource::open(&path)?),
            NodeKind::Evdev => Source::Events(EventSource::open(&path)?),
        };
        let token = match self.conn.reactor() {
            Some(r) => Some(r.register_fd(source.fd(), mio::Interest::READABLE)?),
            None => None,
        };
        Ok(OpenNode {
            info,
            path,
            source,
            token,
        })
    }

    fn try_open(&mut self, now: Now) {
        self.look_at = None;
        let Some(found) = self.find() else {
            if !self.said_waiting {
                self.said_waiting = true;
                let text = format!(
                    "waiting for {} ({}) to be plugged in",
                    self.name,
                    self.describe()
                );
                self.text(TextSeverity::Warning, &text);
                self.tell(DeviceStatus::Waiting {
                    device: self.describe(),
                });
            }
            if self.hub.generation().is_none() {
                self.look_at = Some(now.mono + RESCAN_WITHOUT_WATCHER);
            }
            return;
        };
        let mut opened = Vec::with_capacity(found.len());
        for (i, (info, path)) in found.into_iter().enumerate() {
            match self.open_one(self.wants[i].kind, info, path.clone()) {
                Ok(n) => opened.push(n),
                Err(e) => {
                    for n in opened.drain(..) {
                        self.forget(n);
                    }
                    if self.last_problem.is_none() {
                        self.tell(DeviceStatus::CannotOpen {
                            port: path.display().to_string(),
                            reason: OpenFailure::from_io(&e),
                        });
                    }
                    let early = self.appeared.map_or(true, |t| now.mono < t + EARLY_WINDOW);
                    let retry = if early { EARLY_RETRY } else { LATE_RETRY };
                    self.look_at = Some(now.mono + retry);
                    self.problem(
                        TextSeverity::Error,
                        format!(
                            "cannot open {} for {}: {e}; trying again every {:?}",
                            path.display(),
                            self.name,
                            retry
                        ),
                    );
                    return;
                }
            }
        }
        for n in &opened {
            self.hub.claim(n.path.clone());
        }
        self.nodes = opened;
        self.opens += 1;
        let what = self
            .nodes
            .iter()
            .map(|n| match &n.info {
                Some(i) => {
                    let (v, p) = i.ids();
                    format!("{} ({}, {v:04x}:{p:04x})", n.path.display(), i.name())
                }
                None => n.path.display().to_string(),
            })
            .collect::<Vec<_>>()
            .join(", ");
        let text = if self.was_lost {
            format!("{} is back: {what}", self.name)
        } else {
            format!("{} opened {what}", self.name)
        };
        self.text(TextSeverity::Normal, &text);
        self.tell(DeviceStatus::Opened { port: what });
        self.said_waiting = false;
        self.was_lost = false;
        self.last_problem = None;
        let infos: Vec<Option<NodeInfo>> = self.nodes.iter().map(|n| n.info.clone()).collect();
        if self.driver.wants_descriptor() {
            for (i, n) in self.nodes.iter().enumerate() {
                // sysfs first (it also works for simulated nodes), then the ioctl.
                let from_sysfs = n
                    .info
                    .as_ref()
                    .and_then(NodeInfo::hid)
                    .map(|h| h.report_descriptor())
                    .filter(|r| r.as_ref().is_ok_and(|d| !d.is_empty()));
                let d = match (from_sysfs, &n.source) {
                    (Some(r), _) => r,
                    (None, Source::Report(s)) => s.report_descriptor(),
                    (None, Source::Events(_)) => Err(io::Error::new(
                        io::ErrorKind::Unsupported,
                        "an input event node has no report descriptor",
                    )),
                };
                match &d {
                    Ok(bytes) => self.driver.descriptor(i, Ok(bytes)),
                    Err(e) => self
                        .driver
                        .descriptor(i, Err(io::Error::new(e.kind(), e.to_string()))),
                }
            }
        }
        let mut ops = self.ops.take();
        self.driver.opened(now, &infos, &mut ops);
        self.carry_out(now, ops);
    }

    fn forget(&self, n: OpenNode) {
        if let (Some(r), Some(t)) = (self.conn.reactor(), n.token) {
            r.deregister_fd(n.source.fd(), t);
        }
        self.hub.release(&n.path);
    }

    /// The device (or one of its nodes) went away: close everything, say so, wait for it.
    fn lost(&mut self, now: Now, node: usize, why: &str) {
        let path = self.nodes.get(node).map(|n| n.path.display().to_string());
        for n in std::mem::take(&mut self.nodes) {
            self.forget(n);
        }
        self.driver.closed(now);
        self.was_lost = true;
        self.said_waiting = true;
        let text = format!(
            "{} unplugged ({}: {why}); waiting for it to come back",
            self.name,
            path.as_deref().unwrap_or_default()
        );
        self.text(TextSeverity::Error, &text);
        self.tell(DeviceStatus::Lost {
            port: path.unwrap_or_default(),
            reason: why.to_string(),
        });
        self.last_problem = None;
        if self.hub.generation().is_none() {
            self.look_at = Some(now.mono + RESCAN_WITHOUT_WATCHER);
        }
    }

    /// Carries out the driver's requests, in order (a feature read answers at once and may
    /// bring more requests).
    fn carry_out(&mut self, now: Now, mut ops: HidOps) {
        let mut rounds = 0;
        while !ops.is_empty() && rounds < 8 {
            rounds += 1;
            let mut next = HidOps::new();
            for op in ops.ops().iter().copied() {
                let (interface, result) = match op {
                    HidOp::Output {
                        interface,
                        start,
                        len,
                    } => (
                        interface,
                        self.with_report(interface, |s| s.write_output(ops.bytes(start, len))),
                    ),
                    HidOp::SetFeature {
                        interface,
                        start,
                        len,
                    } => (
                        interface,
                        self.with_report(interface, |s| s.set_feature(ops.bytes(start, len))),
                    ),
                    HidOp::GetFeature { interface, id, len } => {
                        let len = len.clamp(1, MAX_REPORT);
                        let mut buf = vec![0u8; len];
                        buf[0] = id;
                        let r = self.with_report(interface, |s| s.get_feature(&mut buf));
                        match r {
                            Ok(n) => self.driver.feature(
                                interface,
                                Ok(&buf[..n.min(len)]),
                                now,
                                &mut next,
                            ),
                            Err(e) => self.driver.feature(interface, Err(e), now, &mut next),
                        }
                        continue;
                    }
                };
                if let Err(e) = result {
                    let path = self
                        .nodes
                        .get(interface)
                        .map(|n| n.path.display().to_string())
                        .unwrap_or_default();
                    self.problem(
                        TextSeverity::Warning,
                        format!("{}: cannot write to {path}: {e}", self.name),
                    );
                }
            }
            ops = next;
        }
        self.ops.restore(ops);
    }

    fn with_report(
        &self,
        interface: usize,
        f: impl FnOnce(&ReportSource) -> io::Result<usize>,
    ) -> io::Result<usize> {
        match self.nodes.get(interface).map(|n| &n.source) {
            Some(Source::Report(s)) => f(s),
            Some(Source::Events(_)) => Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "an input event node takes no reports",
            )),
            None => Err(io::Error::new(
                io::ErrorKind::NotConnected,
                "the device is not open",
            )),
        }
    }

    /// Reads every node that is readable, handing each report to the driver.
    fn read_all(&mut self, now: Now) {
        for i in 0..self.nodes.len() {
            let at = match (self.conn.reactor(), self.nodes[i].token) {
                (Some(r), Some(t)) => {
                    let ready = r.take(t);
                    if !ready.readable {
                        continue;
                    }
                    ready.woke.unwrap_or(now)
                }
                _ => now,
            };
            loop {
                let Some(node) = self.nodes.get_mut(i) else {
                    return;
                };
                let result = match &mut node.source {
                    Source::Report(s) => s.read(&mut self.buf[..]).map(|n| (n, 0)),
                    Source::Events(s) => s
                        .read_records(&mut self.buf[..EVENT_LEN * EVENTS_PER_READ])
                        .map(|k| (EVENT_LEN, k)),
                };
                match result {
                    Ok((0, _)) => {
                        self.lost(now, i, "end of file");
                        return;
                    }
                    Ok((n, 0)) if matches!(node.source, Source::Report(_)) => {
                        self.reports += 1;
                        let mut ops = self.ops.take();
                        self.driver.report(i, &self.buf[..n], at, &mut ops);
                        self.carry_out(now, ops);
                    }
                    Ok((len, records)) => {
                        for k in 0..records {
                            self.reports += 1;
                            let mut ops = self.ops.take();
                            self.driver
                                .report(i, &self.buf[k * len..(k + 1) * len], at, &mut ops);
                            self.carry_out(now, ops);
                        }
                    }
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        // An unplugged hidraw node reads EIO (then ENODEV); a pipe whose
                        // writer left, end of file.
                        self.lost(now, i, &e.to_string());
                        return;
                    }
                }
            }
        }
    }

    /// After a hot-plug event: a node sysfs no longer lists is gone (a device can vanish
    /// before its reads fail).
    fn check_still_there(&mut self, now: Now) {
        for i in 0..self.nodes.len() {
            let gone = match &self.nodes[i].info {
                Some(info) => {
                    let node = info.node().to_string();
                    let tree = self.hub.tree();
                    match info {
                        NodeInfo::Hid(_) => sysfs::hidraw_info(tree, &node).is_none(),
                        NodeInfo::Input(_) => sysfs::input_info(tree, &node).is_none(),
                    }
                }
                None => !self.nodes[i].path.exists(),
            };
            if gone {
                self.lost(now, i, "removed");
                return;
            }
        }
    }
}

impl<D: HidDriver> Drop for HidDevice<D> {
    fn drop(&mut self) {
        if self.nodes.is_empty() {
            return;
        }
        let mut ops = self.ops.take();
        self.driver.shutdown(&mut ops);
        if let Some(now) = self.last_now {
            self.carry_out(now, ops);
        }
        for n in std::mem::take(&mut self.nodes) {
            self.forget(n);
        }
    }
}

impl<D: HidDriver> ServerDevice for HidDevice<D> {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        self.last_now = Some(now);
        let generation = self.hub.generation();
        let changed = generation.is_some() && generation != self.seen;
        if changed {
            if self.seen.is_some() {
                self.appeared = Some(now.mono);
            }
            self.seen = generation;
        }
        if self.nodes.is_empty() {
            let due = self.look_at.is_some_and(|t| now.mono >= t);
            if changed
                || due
                || self.opens == 0 && !self.said_waiting && self.last_problem.is_none()
            {
                self.try_open(now);
            }
        } else {
            if changed {
                self.check_still_there(now);
            }
            self.read_all(now);
        }
        if !self.nodes.is_empty() {
            let due = self.driver.next_deadline().is_some_and(|d| now.mono >= d);
            if due {
                let mut ops = self.ops.take();
                self.driver.poll(now, &mut ops);
                self.carry_out(now, ops);
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        if self.nodes.is_empty() {
            self.look_at
        } else {
            self.driver.next_deadline()
        }
    }
}
