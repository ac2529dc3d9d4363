//! What the kernel says about HID and input devices, read from sysfs: no device is opened.
//!
//! Every path starts at a [`DeviceTree`]'s roots, so tests enumerate a fake tree written in a
//! temporary folder exactly as they would `/sys` and `/dev`.
//!
//! # hidraw
//!
//! `sys/class/hidraw/hidrawN/uevent` names the device node (`DEVNAME=hidrawN`, under `dev/`);
//! `sys/class/hidraw/hidrawN/device/` is the HID device, whose `uevent` holds
//!
//! ```text
//! HID_ID=0003:0000046D:0000C626        bus, vendor, product (hex)
//! HID_NAME=3Dconnexion SpaceNavigator
//! HID_PHYS=usb-0000:00:14.0-2/input0   ends in the USB interface number
//! HID_UNIQ=                            the serial number, when the device has one
//! ```
//!
//! and `report_descriptor` the raw report descriptor. The USB interface number is the
//! `bInterfaceNumber` of the HID device's parent (the USB interface) when that file exists,
//! else the `inputN` at the end of `HID_PHYS`, else unknown.
//!
//! # evdev
//!
//! `sys/class/input/eventN/uevent` names the node (`DEVNAME=input/eventN`);
//! `sys/class/input/eventN/device/` is the input device: `name`, `phys`, `uniq`,
//! `id/{bustype,vendor,product}` (hex) and `capabilities/{ev,key,rel,abs}` (bitmaps as hex
//! words, most significant first, separated by spaces).

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// Where sysfs and the device nodes are: `/sys` and `/dev` on a real system, folders of a
/// fake tree in tests.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceTree {
    sys: PathBuf,
    dev: PathBuf,
    fake: bool,
}

impl Default for DeviceTree {
    fn default() -> Self {
        DeviceTree::system()
    }
}

impl DeviceTree {
    /// The system's own: `/sys` and `/dev`, hot-plug from the kernel's uevent socket.
    pub fn system() -> DeviceTree {
        DeviceTree {
            sys: PathBuf::from("/sys"),
            dev: PathBuf::from("/dev"),
            fake: false,
        }
    }

    /// A tree under `root` (`root/sys`, `root/dev`), for device simulators: hot-plug events
    /// arrive on a datagram socket at `root/uevent` instead of the kernel's (see
    /// [`super::hotplug`]).
    pub fn under(root: impl AsRef<Path>) -> DeviceTree {
        let root = root.as_ref();
        DeviceTree {
            sys: root.join("sys"),
            dev: root.join("dev"),
            fake: true,
        }
    }

    /// The sysfs root.
    pub fn sys(&self) -> &Path {
        &self.sys
    }

    /// The device-node root.
    pub fn dev(&self) -> &Path {
        &self.dev
    }

    /// True for a tree made with [`under`](Self::under).
    pub fn is_fake(&self) -> bool {
        self.fake
    }

    /// Where a fake tree's hot-plug socket is.
    pub fn uevent_socket(&self) -> Option<PathBuf> {
        self.fake
            .then(|| self.sys.parent().map(|p| p.join("uevent")))
            .flatten()
    }

    /// A device path from a configuration file (`/dev/hidraw3`, `hidraw3`) inside this tree:
    /// a path under `/dev/` moves to the tree's `dev/`, a bare name is looked up there.
    pub fn node_path(&self, given: &str) -> PathBuf {
        if let Some(rest) = given.strip_prefix("/dev/") {
            self.dev.join(rest)
        } else if !given.contains('/') {
            self.dev.join(given)
        } else {
            PathBuf::from(given)
        }
    }
}

/// The bus a device is on (`HID_ID`'s first field, the input layer's `bustype`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bus(pub u16);

impl Bus {
    /// USB.
    pub const USB: Bus = Bus(0x03);
    /// Bluetooth.
    pub const BLUETOOTH: Bus = Bus(0x05);

    /// A short name for listings.
    pub fn label(self) -> &'static str {
        match self.0 {
            0x03 => "usb",
            0x05 => "bluetooth",
            0x06 => "virtual",
            0x11 => "i8042",
            0x18 => "i2c",
            _ => "other",
        }
    }
}

/// One hidraw node, as sysfs describes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HidInfo {
    /// The node's name, `hidrawN`.
    pub node: String,
    /// Its number `N` (enumeration order).
    pub number: u32,
    /// The device file to open.
    pub devnode: PathBuf,
    /// The bus.
    pub bus: Bus,
    /// USB vendor id.
    pub vendor: u16,
    /// USB product id.
    pub product: u16,
    /// USB interface number, when known.
    pub interface: Option<i32>,
    /// The kernel's name for it (manufacturer and product strings).
    pub name: String,
    /// Physical path (`usb-0000:00:14.0-2/input0`).
    pub phys: String,
    /// Serial number (empty when the device has none).
    pub serial: String,
    /// The HID device's sysfs folder (for the report descriptor).
    pub sys_device: PathBuf,
}

impl HidInfo {
    /// The device's report descriptor, as sysfs keeps it.
    pub fn report_descriptor(&self) -> io::Result<Vec<u8>> {
        fs::read(self.sys_device.join("report_descriptor"))
    }
}

/// The `KEY=value` lines of a sysfs `uevent` file (or the fields of a uevent message).
pub fn uevent_field<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    text.lines().find_map(|l| {
        l.strip_prefix(key)
            .and_then(|rest| rest.strip_prefix('='))
            .map(str::trim)
    })
}

fn read_text(p: &Path) -> Option<String> {
    fs::read_to_string(p).ok()
}

/// `HID_ID=BBBB:VVVVVVVV:PPPPPPPP` → (bus, vendor, product).
pub fn parse_hid_id(s: &str) -> Option<(u16, u16, u16)> {
    let mut it = s.split(':');
    let bus = u32::from_str_radix(it.next()?, 16).ok()?;
    let vendor = u32::from_str_radix(it.next()?, 16).ok()?;
    let product = u32::from_str_radix(it.next()?, 16).ok()?;
    if it.next().is_some() {
        return None;
    }
    Some((bus as u16, vendor as u16, product as u16))
}

/// The `inputN` at the end of a `HID_PHYS` (`usb-0000:00:14.0-2/input1` → 1).
pub fn interface_from_phys(phys: &str) -> Option<i32> {
    let tail = phys.rsplit('/').next()?;
    tail.strip_prefix("input")?.parse().ok()
}

/// The number at the end of a node name (`hidraw12` → 12, `event3` → 3).
pub fn node_number(name: &str) -> Option<u32> {
    let digits = name.trim_start_matches(|c: char| !c.is_ascii_digit());
    (!digits.is_empty() && name.ends_with(digits))
        .then(|| digits.parse().ok())
        .flatten()
}

/// Folder entries of `dir` whose names start with `prefix` and end in a number, sorted by it.
fn numbered_entries(dir: &Path, prefix: &str) -> Vec<(u32, String)> {
    let Ok(rd) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<(u32, String)> = rd
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let n = name.strip_prefix(prefix)?.parse().ok()?;
            Some((n, name))
        })
        .collect();
    v.sort();
    v
}

fn devnode(tree: &DeviceTree, class_dir: &Path, fallback: &str) -> PathBuf {
    let name = read_text(&class_dir.join("uevent"))
        .and_then(|t| uevent_field(&t, "DEVNAME").map(str::to_string))
        .unwrap_or_else(|| fallback.to_string());
    tree.dev.join(name)
}

/// Reads one hidraw node's description; `None` when sysfs lacks what identifies it.
pub fn hidraw_info(tree: &DeviceTree, node: &str) -> Option<HidInfo> {
    let number = node.strip_prefix("hidraw")?.parse().ok()?;
    let class_dir = tree.sys.join("class/hidraw").join(node);
    let sys_device = class_dir.join("device");
    let uevent = read_text(&sys_device.join("uevent"))?;
    let (bus, vendor, product) = parse_hid_id(uevent_field(&uevent, "HID_ID")?)?;
    let phys = uevent_field(&uevent, "HID_PHYS").unwrap_or("").to_string();
    let interface = fs::canonicalize(&sys_device)
        .ok()
        .and_then(|d| d.parent().map(|p| p.join("bInterfaceNumber")))
        .and_then(|f| read_text(&f))
        .and_then(|t| i32::from_str_radix(t.trim(), 16).ok())
        .or_else(|| interface_from_phys(&phys));
    Some(HidInfo {
        devnode: devnode(tree, &class_dir, node),
        node: node.to_string(),
        number,
        bus: Bus(bus),
        vendor,
        product,
        interface,
        name: uevent_field(&uevent, "HID_NAME").unwrap_or("").to_string(),
        phys,
        serial: uevent_field(&uevent, "HID_UNIQ").unwrap_or("").to_string(),
        sys_device,
    })
}

/// Every hidraw node sysfs knows, in node-number order.
pub fn enumerate_hidraw(tree: &DeviceTree) -> Vec<HidInfo> {
    numbered_entries(&tree.sys.join("class/hidraw"), "hidraw")
        .into_iter()
        .filter_map(|(_, name)| hidraw_info(tree, &name))
        .collect()
}

/// A capability bitmap from sysfs (`"1 0 120013"`: words most significant first).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Bitmap(Vec<u64>);

impl Bitmap {
    /// Parses sysfs's text; words that are not hex count as zero.
    pub fn parse(text: &str) -> Bitmap {
        let mut words: Vec<u64> = text
            .split_whitespace()
            .map(|w| u64::from_str_radix(w, 16).unwrap_or(0))
            .collect();
        words.reverse();
        Bitmap(words)
    }

    /// Whether bit `n` is set.
    pub fn has(&self, n: u32) -> bool {
        let (w, b) = ((n / 64) as usize, n % 64);
        self.0.get(w).is_some_and(|word| word & (1 << b) != 0)
    }

    /// The set bits, in order.
    pub fn bits(&self) -> impl Iterator<Item = u32> + '_ {
        self.0.iter().enumerate().flat_map(|(w, word)| {
            (0..64).filter_map(move |b| (word & (1 << b) != 0).then_some(w as u32 * 64 + b))
        })
    }
}

/// One evdev node, as sysfs describes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputInfo {
    /// The node's name, `eventN`.
    pub node: String,
    /// Its number `N`.
    pub number: u32,
    /// The device file to open.
    pub devnode: PathBuf,
    /// The device's name (what `EVIOCGNAME` answers).
    pub name: String,
    /// Physical path.
    pub phys: String,
    /// The bus.
    pub bus: Bus,
    /// Vendor id.
    pub vendor: u16,
    /// Product id.
    pub product: u16,
    /// Event types (`EV_KEY`, `EV_REL`, `EV_ABS`, …).
    pub ev: Bitmap,
    /// Keys and buttons.
    pub key: Bitmap,
    /// Relative axes.
    pub rel: Bitmap,
    /// Absolute axes.
    pub abs: Bitmap,
}

fn read_hex(p: &Path) -> u16 {
    read_text(p)
        .and_then(|t| u16::from_str_radix(t.trim(), 16).ok())
        .unwrap_or(0)
}

/// Reads one evdev node's description; `None` when sysfs lacks its name.
pub fn input_info(tree: &DeviceTree, node: &str) -> Option<InputInfo> {
    let number = node.strip_prefix("event")?.parse().ok()?;
    let class_dir = tree.sys.join("class/input").join(node);
    let dev = class_dir.join("device");
    let name = read_text(&dev.join("name"))?
        .trim_end_matches('\n')
        .to_string();
    let caps =
        |f: &str| Bitmap::parse(&read_text(&dev.join("capabilities").join(f)).unwrap_or_default());
    Some(InputInfo {
        devnode: devnode(tree, &class_dir, &format!("input/{node}")),
        node: node.to_string(),
        number,
        name,
        phys: read_text(&dev.join("phys"))
            .unwrap_or_default()
            .trim()
            .to_string(),
        bus: Bus(read_hex(&dev.join("id/bustype"))),
        vendor: read_hex(&dev.join("id/vendor")),
        product: read_hex(&dev.join("id/product")),
        ev: caps("ev"),
        key: caps("key"),
        rel: caps("rel"),
        abs: caps("abs"),
    })
}

/// Every evdev node sysfs knows, in node-number order.
pub fn enumerate_input(tree: &DeviceTree) -> Vec<InputInfo> {
    numbered_entries(&tree.sys.join("class/input"), "event")
        .into_iter()
        .filter_map(|(_, name)| input_info(tree, &name))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hid::fake::FakeTree;

    #[test]
    fn hid_id_and_phys_parse() {
        assert_eq!(
            parse_hid_id("0003:0000046D:0000C626"),
            Some((3, 0x046d, 0xc626))
        );
        assert_eq!(parse_hid_id("0003:046D"), None);
        assert_eq!(parse_hid_id("x:1:2"), None);
        assert_eq!(interface_from_phys("usb-0000:00:14.0-2/input1"), Some(1));
        assert_eq!(interface_from_phys("usb-0000:00:14.0-2"), None);
        assert_eq!(node_number("hidraw12"), Some(12));
        assert_eq!(node_number("hidraw"), None);
    }

    #[test]
    fn bitmaps_read_most_significant_word_first() {
        let b = Bitmap::parse("1 0 120013\n");
        assert!(b.has(0) && b.has(1) && b.has(4) && b.has(17) && b.has(20));
        assert!(b.has(128));
        assert!(!b.has(2) && !b.has(64));
        assert_eq!(b.bits().collect::<Vec<_>>(), vec![0, 1, 4, 17, 20, 128]);
        assert!(!Bitmap::parse("").has(0));
    }

    #[test]
    fn a_fake_tree_enumerates_in_node_order_with_every_field() {
        let t = FakeTree::new();
        t.add_hidraw(10, 0x046d, 0xc626, 0, "3Dconnexion SpaceNavigator", "SN1");
        t.add_hidraw(2, 0x1532, 0x0300, 1, "Razer Hydra", "");
        let list = enumerate_hidraw(&t.tree());
        assert_eq!(list.len(), 2);
        assert_eq!(list[0].node, "hidraw2");
        assert_eq!(list[0].interface, Some(1));
        assert_eq!((list[0].vendor, list[0].product), (0x1532, 0x0300));
        assert_eq!(list[1].node, "hidraw10");
        assert_eq!(list[1].name, "3Dconnexion SpaceNavigator");
        assert_eq!(list[1].serial, "SN1");
        assert_eq!(list[1].bus, Bus::USB);
        assert_eq!(list[1].devnode, t.tree().dev().join("hidraw10"));
        t.remove_hidraw(2);
        assert_eq!(enumerate_hidraw(&t.tree()).len(), 1);
    }

    #[test]
    fn interface_number_prefers_the_usb_interface_file() {
        let t = FakeTree::new();
        t.add_hidraw(0, 1, 2, 3, "x", "");
        // A parent folder with bInterfaceNumber (the real layout: .../1-2:1.0/0003:...).
        let dev = t.tree().sys().join("class/hidraw/hidraw0/device");
        let real = t
            .tree()
            .sys()
            .join("devices/usb1/1-2:1.5/0003:0001:0002.0001");
        std::fs::create_dir_all(&real).unwrap();
        for f in ["uevent", "report_descriptor"] {
            std::fs::copy(dev.join(f), real.join(f)).unwrap();
        }
        std::fs::write(real.parent().unwrap().join("bInterfaceNumber"), "05\n").unwrap();
        std::fs::remove_dir_all(&dev).unwrap();
        std::os::unix::fs::symlink(&real, &dev).unwrap();
        assert_eq!(
            hidraw_info(&t.tree(), "hidraw0").unwrap().interface,
            Some(5)
        );
    }

    #[test]
    fn input_nodes_carry_name_ids_and_capabilities() {
        let t = FakeTree::new();
        t.add_input(
            3,
            "USB Optical Mouse",
            0x046d,
            0xc077,
            "17",
            "70000 0 0 0 0",
            "103",
            "",
        );
        t.add_input(
            1,
            "AT Translated Set 2 keyboard",
            1,
            1,
            "120013",
            "ffff",
            "",
            "",
        );
        let list = enumerate_input(&t.tree());
        assert_eq!(list.len(), 2);
        assert_eq!(list[0].name, "AT Translated Set 2 keyboard");
        let m = &list[1];
        assert_eq!(m.devnode, t.tree().dev().join("input/event3"));
        assert!(m.ev.has(1) && m.ev.has(2));
        assert!(m.key.has(0x110) && m.key.has(0x111) && m.key.has(0x112));
        assert!(m.rel.has(0) && m.rel.has(1) && m.rel.has(8));
        assert_eq!((m.vendor, m.product), (0x046d, 0xc077));
    }

    #[test]
    fn configured_paths_move_into_the_tree() {
        let t = DeviceTree::under("/x");
        assert_eq!(t.node_path("/dev/hidraw3"), PathBuf::from("/x/dev/hidraw3"));
        assert_eq!(t.node_path("hidraw3"), PathBuf::from("/x/dev/hidraw3"));
        assert_eq!(t.node_path("/tmp/p"), PathBuf::from("/tmp/p"));
        assert_eq!(
            DeviceTree::system().node_path("/dev/input/event1"),
            PathBuf::from("/dev/input/event1")
        );
        assert_eq!(t.uevent_socket(), Some(PathBuf::from("/x/uevent")));
        assert_eq!(DeviceTree::system().uevent_socket(), None);
    }
}
