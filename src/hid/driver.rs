//! The interface between a driver (sans-IO: report bytes in, VRPN reports out) and the
//! device layer that finds, opens and watches its hidraw or evdev nodes.

use std::io;
use std::path::Path;
use std::time::Instant;

use super::input_event::{BTN_LEFT, EV_KEY, EV_REL, REL_X, REL_Y};
use super::sysfs::{HidInfo, InputInfo};
use crate::time::Now;

/// The two kinds of device node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeKind {
    /// `/dev/hidrawN`: raw HID reports.
    Hidraw,
    /// `/dev/input/eventN`: Linux input events.
    Evdev,
}

/// A node found in sysfs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NodeInfo {
    /// A hidraw node.
    Hid(HidInfo),
    /// An evdev node.
    Input(InputInfo),
}

impl NodeInfo {
    /// The device file.
    pub fn devnode(&self) -> &Path {
        match self {
            NodeInfo::Hid(i) => &i.devnode,
            NodeInfo::Input(i) => &i.devnode,
        }
    }

    /// The node's name in sysfs (`hidraw3`, `event5`).
    pub fn node(&self) -> &str {
        match self {
            NodeInfo::Hid(i) => &i.node,
            NodeInfo::Input(i) => &i.node,
        }
    }

    /// The kernel's name for the device.
    pub fn name(&self) -> &str {
        match self {
            NodeInfo::Hid(i) => &i.name,
            NodeInfo::Input(i) => &i.name,
        }
    }

    /// Vendor and product ids.
    pub fn ids(&self) -> (u16, u16) {
        match self {
            NodeInfo::Hid(i) => (i.vendor, i.product),
            NodeInfo::Input(i) => (i.vendor, i.product),
        }
    }

    /// The hidraw description, for a hidraw node.
    pub fn hid(&self) -> Option<&HidInfo> {
        match self {
            NodeInfo::Hid(i) => Some(i),
            NodeInfo::Input(_) => None,
        }
    }

    /// The evdev description, for an evdev node.
    pub fn input(&self) -> Option<&InputInfo> {
        match self {
            NodeInfo::Input(i) => Some(i),
            NodeInfo::Hid(_) => None,
        }
    }
}

/// One way of recognising a device.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Select {
    /// USB vendor and product ids: a device whose `product & mask` equals `product & mask`
    /// (`mask` 0xFFFF for an exact product).
    Product {
        /// Vendor id.
        vendor: u16,
        /// Product id (the bits under `mask` count).
        product: u16,
        /// Which product bits count.
        mask: u16,
    },
    /// The kernel's name for the device, exactly.
    Name(String),
    /// The device node (`/dev/hidraw3`, `hidraw3`, `/dev/input/event2`, or any file).
    Path(String),
    /// An evdev node that moves a pointer: relative X and Y and a left button.
    Mouse,
}

/// Which interface number a device must have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InterfaceRule {
    /// Any.
    Any,
    /// Exactly this one.
    Is(i32),
    /// This one, or unknown (a device whose bus has no interface numbers).
    IsOrUnknown(i32),
}

/// The node a driver wants for one of its interfaces: see [`HidDriver::interfaces`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HidMatch {
    /// Hidraw or evdev.
    pub kind: NodeKind,
    /// Accepted if any of these matches.
    pub any_of: Vec<Select>,
    /// The interface number.
    pub interface: InterfaceRule,
    /// Take the `nth` node that matches (0: the first that no other device holds).
    pub nth: usize,
}

impl HidMatch {
    /// A device with these ids, any interface.
    pub fn product(vendor: u16, product: u16) -> HidMatch {
        HidMatch {
            kind: NodeKind::Hidraw,
            any_of: vec![Select::Product {
                vendor,
                product,
                mask: 0xFFFF,
            }],
            interface: InterfaceRule::Any,
            nth: 0,
        }
    }

    /// An evdev node picked by `select`.
    pub fn evdev(select: Select) -> HidMatch {
        HidMatch {
            kind: NodeKind::Evdev,
            any_of: vec![select],
            interface: InterfaceRule::Any,
            nth: 0,
        }
    }

    /// A node of `kind` picked by `select`.
    pub fn of(kind: NodeKind, select: Select) -> HidMatch {
        HidMatch {
            kind,
            any_of: vec![select],
            interface: InterfaceRule::Any,
            nth: 0,
        }
    }

    /// Also accepts these ids.
    pub fn or_product(mut self, vendor: u16, product: u16) -> HidMatch {
        self.any_of.push(Select::Product {
            vendor,
            product,
            mask: 0xFFFF,
        });
        self
    }

    /// The `n`th matching node (counting from 0), whether or not another device holds the
    /// ones before it.
    pub fn nth(mut self, n: usize) -> HidMatch {
        self.nth = n;
        self
    }

    /// Only this interface.
    pub fn interface(mut self, rule: InterfaceRule) -> HidMatch {
        self.interface = rule;
        self
    }

    /// The configured path when the match is by path alone (such a node is opened even
    /// when sysfs does not know it: a pipe standing in for an evdev node).
    pub fn path(&self) -> Option<&str> {
        match self.any_of.as_slice() {
            [Select::Path(p)] => Some(p),
            _ => None,
        }
    }

    /// Whether `info` is such a device (`dev` is the tree's device root, for configured
    /// `/dev/…` paths).
    pub fn accepts(&self, info: &NodeInfo, dev: &Path) -> bool {
        let kind_ok = matches!(
            (self.kind, info),
            (NodeKind::Hidraw, NodeInfo::Hid(_)) | (NodeKind::Evdev, NodeInfo::Input(_))
        );
        let interface = info.hid().and_then(|h| h.interface);
        let iface_ok = match self.interface {
            InterfaceRule::Any => true,
            InterfaceRule::Is(i) => interface == Some(i),
            InterfaceRule::IsOrUnknown(i) => interface.map_or(true, |n| n == i || n < 0),
        };
        let (v, pid) = info.ids();
        kind_ok
            && iface_ok
            && self.any_of.iter().any(|s| match s {
                Select::Product {
                    vendor,
                    product,
                    mask,
                } => v == *vendor && (pid & mask) == (product & mask),
                Select::Name(n) => info.name() == n,
                Select::Path(p) => {
                    info.devnode() == Path::new(p)
                        || info.node() == p
                        || p.strip_prefix("/dev/")
                            .is_some_and(|rest| info.devnode() == dev.join(rest))
                }
                Select::Mouse => info.input().is_some_and(|i| {
                    i.ev.has(EV_REL.into())
                        && i.ev.has(EV_KEY.into())
                        && i.rel.has(REL_X.into())
                        && i.rel.has(REL_Y.into())
                        && i.key.has(BTN_LEFT.into())
                }),
            })
    }

    /// How the device is described to an operator (`046d:c626`, `"name"`, `/dev/hidraw3`).
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self
            .any_of
            .iter()
            .map(|s| match s {
                Select::Product {
                    vendor,
                    product,
                    mask: 0xFFFF,
                } => format!("{vendor:04x}:{product:04x}"),
                Select::Product {
                    vendor,
                    product,
                    mask,
                } => format!("{vendor:04x}:{:04x}/{mask:04x}", product & mask),
                Select::Name(n) => format!("\"{n}\""),
                Select::Path(p) => p.clone(),
                Select::Mouse => "a mouse".to_string(),
            })
            .collect();
        let ids = parts.join(" or ");
        match self.interface {
            InterfaceRule::Any => ids,
            InterfaceRule::Is(i) | InterfaceRule::IsOrUnknown(i) => {
                format!("{ids}, interface {i}")
            }
        }
    }
}

/// One request a driver makes of its device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HidOp {
    /// Write an output report (bytes `start..start + len` of [`HidOps::bytes`]).
    Output {
        /// Which of the driver's interfaces.
        interface: usize,
        /// Offset in the byte buffer.
        start: usize,
        /// Length.
        len: usize,
    },
    /// Send a feature report.
    SetFeature {
        /// Which of the driver's interfaces.
        interface: usize,
        /// Offset in the byte buffer.
        start: usize,
        /// Length.
        len: usize,
    },
    /// Read a feature report; the answer goes to [`HidDriver::feature`].
    GetFeature {
        /// Which of the driver's interfaces.
        interface: usize,
        /// Report id.
        id: u8,
        /// Most bytes wanted (report id included).
        len: usize,
    },
}

/// The requests of one driver call, carried out in order right after it returns. Reused:
/// no allocation once warmed up.
#[derive(Debug, Default)]
pub struct HidOps {
    ops: Vec<HidOp>,
    bytes: Vec<u8>,
}

impl HidOps {
    /// An empty list.
    pub fn new() -> HidOps {
        HidOps {
            ops: Vec::with_capacity(8),
            bytes: Vec::with_capacity(256),
        }
    }

    fn push_bytes(&mut self, bytes: &[u8]) -> (usize, usize) {
        let start = self.bytes.len();
        self.bytes.extend_from_slice(bytes);
        (start, bytes.len())
    }

    /// Writes an output report (`report[0]` is the report id, 0 when the device has none).
    pub fn output(&mut self, interface: usize, report: &[u8]) {
        let (start, len) = self.push_bytes(report);
        self.ops.push(HidOp::Output {
            interface,
            start,
            len,
        });
    }

    /// Sends a feature report (`report[0]` is the report id).
    pub fn set_feature(&mut self, interface: usize, report: &[u8]) {
        let (start, len) = self.push_bytes(report);
        self.ops.push(HidOp::SetFeature {
            interface,
            start,
            len,
        });
    }

    /// Asks for feature report `id`, at most `len` bytes.
    pub fn get_feature(&mut self, interface: usize, id: u8, len: usize) {
        self.ops.push(HidOp::GetFeature { interface, id, len });
    }

    /// The requests, in order.
    pub fn ops(&self) -> &[HidOp] {
        &self.ops
    }

    /// The bytes of a request.
    pub fn bytes(&self, start: usize, len: usize) -> &[u8] {
        &self.bytes[start..start + len]
    }

    /// True when nothing was asked.
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// Forgets every request, keeping the capacity.
    pub fn clear(&mut self) {
        self.ops.clear();
        self.bytes.clear();
    }

    /// Takes the requests out (the device layer carries them out while the driver runs
    /// again).
    pub(crate) fn take(&mut self) -> HidOps {
        std::mem::take(self)
    }

    /// Puts an emptied list back, for its capacity.
    pub(crate) fn restore(&mut self, mut used: HidOps) {
        used.clear();
        if self.ops.is_empty() && self.bytes.is_empty() {
            *self = used;
        }
    }
}

/// A HID device driver, free of I/O and of clocks.
///
/// The device layer finds a hidraw node for each of [`interfaces`](Self::interfaces), opens
/// them all, calls [`opened`](Self::opened), then hands every input report to
/// [`report`](Self::report) with the time its read woke the server. A device that goes away
/// is reported and [`closed`](Self::closed) follows; [`opened`](Self::opened) runs again when
/// it is back.
pub trait HidDriver {
    /// The device's name (its VRPN sender), for messages.
    fn name(&self) -> &str;

    /// The nodes the device needs, all present for it to run (most devices need one; the
    /// Razer Hydra needs its data and its control interface).
    fn interfaces(&self) -> Vec<HidMatch>;

    /// Whether [`descriptor`](Self::descriptor) is wanted (a driver that reads the device's
    /// report descriptor to learn its layout).
    fn wants_descriptor(&self) -> bool {
        false
    }

    /// Interface `interface`'s report descriptor, from sysfs or `HIDIOCGRDESC`, before
    /// [`opened`](Self::opened) (only when [`wants_descriptor`](Self::wants_descriptor)).
    fn descriptor(&mut self, _interface: usize, _descriptor: std::io::Result<&[u8]>) {}

    /// Every interface is open (`nodes[i]` is the one found for `interfaces()[i]`; a node
    /// opened by a configured path that sysfs does not describe has `None`).
    fn opened(&mut self, now: Now, nodes: &[Option<NodeInfo>], ops: &mut HidOps);

    /// One input report from interface `interface`, exactly as hidraw returned it (the
    /// report id first when the device numbers its reports), read at `at`. From an evdev
    /// node, one `input_event` record ([`super::input_event::InputEvent::decode`]).
    fn report(&mut self, interface: usize, report: &[u8], at: Now, ops: &mut HidOps);

    /// The answer to a [`HidOps::get_feature`].
    fn feature(
        &mut self,
        _interface: usize,
        _report: io::Result<&[u8]>,
        _now: Now,
        _ops: &mut HidOps,
    ) {
    }

    /// Time-driven work (keep-alives, mode changes); called at or after
    /// [`next_deadline`](Self::next_deadline) and on every pass the device is open.
    fn poll(&mut self, _now: Now, _ops: &mut HidOps) {}

    /// When [`poll`](Self::poll) is next needed.
    fn next_deadline(&self) -> Option<Instant> {
        None
    }

    /// The device went away (or a node of it did); everything is closed.
    fn closed(&mut self, _now: Now) {}

    /// The server is stopping while the device is open: last words to it (C++ turns the
    /// X-keys LEDs off and puts a Razer Hydra back in gamepad mode).
    fn shutdown(&mut self, _ops: &mut HidOps) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hid::sysfs::Bus;
    use std::path::{Path, PathBuf};

    fn info(vendor: u16, product: u16, interface: Option<i32>) -> NodeInfo {
        NodeInfo::Hid(HidInfo {
            node: "hidraw3".into(),
            number: 3,
            devnode: PathBuf::from("/t/dev/hidraw3"),
            bus: Bus::USB,
            vendor,
            product,
            interface,
            name: "Pad".into(),
            phys: String::new(),
            serial: String::new(),
            sys_device: PathBuf::new(),
        })
    }

    #[test]
    fn products_masks_interfaces_names_and_paths_select() {
        let dev = Path::new("/t/dev");
        let m = HidMatch::product(0x046d, 0xc626);
        assert!(m.accepts(&info(0x046d, 0xc626, Some(0)), dev));
        assert!(!m.accepts(&info(0x046d, 0xc627, Some(0)), dev));
        let masked = HidMatch {
            kind: NodeKind::Hidraw,
            any_of: vec![Select::Product {
                vendor: 0x5d70,
                product: 0x0011,
                mask: 0x0011,
            }],
            interface: InterfaceRule::Any,
            nth: 0,
        };
        assert!(masked.accepts(&info(0x5d70, 0x0013, None), dev));
        assert!(!masked.accepts(&info(0x5d70, 0x0010, None), dev));
        let hydra = HidMatch::product(0x1532, 0x0300).interface(InterfaceRule::Is(1));
        assert!(!hydra.accepts(&info(0x1532, 0x0300, Some(0)), dev));
        assert!(hydra.accepts(&info(0x1532, 0x0300, Some(1)), dev));
        let sp = HidMatch::product(1, 2).interface(InterfaceRule::IsOrUnknown(1));
        assert!(sp.accepts(&info(1, 2, None), dev));
        assert!(!sp.accepts(&info(1, 2, Some(0)), dev));
        let either = HidMatch::product(1, 2).or_product(3, 4);
        assert!(either.accepts(&info(3, 4, None), dev));
        let name = HidMatch::of(NodeKind::Hidraw, Select::Name("Pad".into()));
        assert!(name.accepts(&info(9, 9, None), dev));
        for p in ["/dev/hidraw3", "hidraw3", "/t/dev/hidraw3"] {
            let m = HidMatch::of(NodeKind::Hidraw, Select::Path(p.into()));
            assert!(m.accepts(&info(9, 9, None), dev), "{p}");
        }
        assert_eq!(hydra.describe(), "1532:0300, interface 1");
        assert_eq!(masked.describe(), "5d70:0011/0011");
        // An evdev match never takes a hidraw node.
        assert!(!HidMatch::evdev(Select::Name("Pad".into())).accepts(&info(9, 9, None), dev));
    }

    #[test]
    fn a_mouse_is_recognised_by_its_capabilities() {
        use crate::hid::sysfs::Bitmap;
        let mut i = InputInfo {
            node: "event1".into(),
            number: 1,
            devnode: PathBuf::from("/t/dev/input/event1"),
            name: "m".into(),
            phys: String::new(),
            bus: Bus::USB,
            vendor: 0,
            product: 0,
            ev: Bitmap::parse("7"),
            key: Bitmap::parse("70000 0 0 0 0"),
            rel: Bitmap::parse("103"),
            abs: Bitmap::default(),
        };
        let m = HidMatch::evdev(Select::Mouse);
        assert!(m.accepts(&NodeInfo::Input(i.clone()), Path::new("/t/dev")));
        i.rel = Bitmap::parse("1");
        assert!(!m.accepts(&NodeInfo::Input(i), Path::new("/t/dev")));
    }
}
