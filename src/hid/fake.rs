//! A fake device tree in a temporary folder, for simulators and tests: sysfs entries for
//! hidraw and evdev nodes written as the kernel lays them out, device nodes that are
//! simulator sockets (hidraw) or named pipes (evdev), and uevent messages sent to the tree's
//! hot-plug socket. See [`DeviceTree::under`].

use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::source::NodeListener;
use super::sysfs::DeviceTree;
use super::uevent;

/// A folder removed (with everything in it) when dropped.
#[derive(Debug)]
pub struct TempDir(PathBuf);

impl TempDir {
    /// A new, empty folder under the system's temporary folder.
    pub fn new(tag: &str) -> TempDir {
        static N: AtomicU64 = AtomicU64::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        let p = std::env::temp_dir().join(format!(
            "vrpn-{tag}-{}-{}-{nanos}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&p).expect("cannot create a temporary folder");
        TempDir(p)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fake `/sys` and `/dev`: see the module documentation.
#[derive(Debug)]
pub struct FakeTree {
    dir: TempDir,
}

impl Default for FakeTree {
    fn default() -> Self {
        FakeTree::new()
    }
}

fn write(path: &Path, contents: impl AsRef<[u8]>) {
    if let Some(p) = path.parent() {
        std::fs::create_dir_all(p).expect("cannot create a fake sysfs folder");
    }
    std::fs::write(path, contents).expect("cannot write a fake sysfs file");
}

impl FakeTree {
    /// An empty tree.
    pub fn new() -> FakeTree {
        let dir = TempDir::new("devtree");
        std::fs::create_dir_all(dir.path().join("sys/class/hidraw")).expect("fake sysfs");
        std::fs::create_dir_all(dir.path().join("sys/class/input")).expect("fake sysfs");
        std::fs::create_dir_all(dir.path().join("dev/input")).expect("fake dev");
        FakeTree { dir }
    }

    /// The folder holding `sys/`, `dev/` and `uevent`.
    pub fn root(&self) -> &Path {
        self.dir.path()
    }

    /// The tree, as the device layer sees it.
    pub fn tree(&self) -> DeviceTree {
        DeviceTree::under(self.dir.path())
    }

    /// Describes hidraw node `n` in sysfs (no device node yet: see
    /// [`listen_hidraw`](Self::listen_hidraw)).
    pub fn add_hidraw(
        &self,
        n: u32,
        vendor: u16,
        product: u16,
        interface: i32,
        name: &str,
        serial: &str,
    ) {
        let class = self.root().join(format!("sys/class/hidraw/hidraw{n}"));
        write(
            &class.join("uevent"),
            format!("MAJOR=241\nMINOR={n}\nDEVNAME=hidraw{n}\n"),
        );
        write(
            &class.join("device/uevent"),
            format!(
                "DRIVER=hid-generic\nHID_ID=0003:{vendor:08X}:{product:08X}\nHID_NAME={name}\n\
                 HID_PHYS=usb-0000:00:14.0-{n}/input{interface}\nHID_UNIQ={serial}\n\
                 MODALIAS=hid:b0003g0001v{vendor:08X}p{product:08X}\n"
            ),
        );
        write(&class.join("device/report_descriptor"), []);
    }

    /// Sets hidraw node `n`'s report descriptor.
    pub fn set_report_descriptor(&self, n: u32, descriptor: &[u8]) {
        write(
            &self.root().join(format!(
                "sys/class/hidraw/hidraw{n}/device/report_descriptor"
            )),
            descriptor,
        );
    }

    /// A simulator's socket at hidraw node `n`'s device file.
    pub fn listen_hidraw(&self, n: u32) -> io::Result<NodeListener> {
        NodeListener::bind(&self.root().join(format!("dev/hidraw{n}")))
    }

    /// Removes hidraw node `n` from sysfs and its device file.
    pub fn remove_hidraw(&self, n: u32) {
        let _ = std::fs::remove_dir_all(self.root().join(format!("sys/class/hidraw/hidraw{n}")));
        let _ = std::fs::remove_file(self.root().join(format!("dev/hidraw{n}")));
    }

    /// Describes evdev node `n` in sysfs; capabilities are sysfs's hex words.
    #[allow(clippy::too_many_arguments)]
    pub fn add_input(
        &self,
        n: u32,
        name: &str,
        vendor: u16,
        product: u16,
        ev: &str,
        key: &str,
        rel: &str,
        abs: &str,
    ) {
        let class = self.root().join(format!("sys/class/input/event{n}"));
        write(
            &class.join("uevent"),
            format!("MAJOR=13\nMINOR={}\nDEVNAME=input/event{n}\n", 64 + n),
        );
        let dev = class.join("device");
        write(&dev.join("name"), format!("{name}\n"));
        write(&dev.join("phys"), format!("usb-0000:00:14.0-{n}/input0\n"));
        write(&dev.join("id/bustype"), "0003\n");
        write(&dev.join("id/vendor"), format!("{vendor:04x}\n"));
        write(&dev.join("id/product"), format!("{product:04x}\n"));
        for (f, v) in [("ev", ev), ("key", key), ("rel", rel), ("abs", abs)] {
            write(&dev.join("capabilities").join(f), format!("{v}\n"));
        }
    }

    /// Makes evdev node `n`'s device file a named pipe; returns its path.
    pub fn fifo_input(&self, n: u32) -> io::Result<PathBuf> {
        let p = self.root().join(format!("dev/input/event{n}"));
        let _ = std::fs::remove_file(&p);
        nix::unistd::mkfifo(&p, nix::sys::stat::Mode::from_bits_truncate(0o600))
            .map_err(|e| io::Error::from_raw_os_error(e as i32))?;
        Ok(p)
    }

    /// Removes evdev node `n` from sysfs and its device file.
    pub fn remove_input(&self, n: u32) {
        let _ = std::fs::remove_dir_all(self.root().join(format!("sys/class/input/event{n}")));
        let _ = std::fs::remove_file(self.root().join(format!("dev/input/event{n}")));
    }

    /// Sends the tree's watcher the uevent the kernel would (`"add"`/`"remove"`,
    /// `"hidraw"`/`"input"`, `"hidraw0"`/`"input/event3"`). Fails when nothing listens yet.
    pub fn uevent(&self, action: &str, subsystem: &str, devname: &str) -> io::Result<()> {
        let path = self
            .tree()
            .uevent_socket()
            .expect("a fake tree has a uevent socket");
        let msg = uevent::message(
            action,
            subsystem,
            devname,
            &format!("/devices/fake/{subsystem}/{devname}"),
        );
        std::os::unix::net::UnixDatagram::unbound()?.send_to(&msg, path)?;
        Ok(())
    }
}
