//! Kernel uevent messages (the netlink `NETLINK_KOBJECT_UEVENT` multicast group 1): parsing,
//! free of I/O.
//!
//! A message is a header `ACTION@DEVPATH` and `KEY=value` fields, each ended by a NUL byte:
//!
//! ```text
//! add@/devices/pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0/0003:046D:C626.0001/hidraw/hidraw0\0
//! ACTION=add\0DEVPATH=/devices/…/hidraw/hidraw0\0SUBSYSTEM=hidraw\0MAJOR=241\0MINOR=0\0
//! DEVNAME=hidraw0\0SEQNUM=3021\0
//! ```
//!
//! Messages udev re-broadcasts (group 2) start with `libudev\0` and a binary header; they are
//! not for us and are ignored. A message is only a hint that something changed: the device
//! layer reads sysfs again for the truth, so a forged or garbled message costs one look at
//! sysfs, never a wrong device.

/// What happened.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// A device appeared.
    Add,
    /// A device went away.
    Remove,
    /// Anything else (`change`, `bind`, `unbind`, `move`, …).
    Other,
}

/// One parsed uevent, borrowing the message's bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Uevent<'a> {
    /// The action.
    pub action: Action,
    /// `SUBSYSTEM` (`hidraw`, `input`, `usb`, …).
    pub subsystem: &'a str,
    /// `DEVNAME` (`hidraw0`, `input/event3`), empty when the device has no node.
    pub devname: &'a str,
    /// `DEVPATH`.
    pub devpath: &'a str,
}

impl Uevent<'_> {
    /// True when the event concerns a node this crate reads (a hidraw or evdev node).
    pub fn is_device_node(&self) -> bool {
        self.subsystem == "hidraw"
            || (self.subsystem == "input" && self.devname.starts_with("input/event"))
    }
}

/// Parses one message; `None` for a udev re-broadcast or something that is not a uevent.
pub fn parse(msg: &[u8]) -> Option<Uevent<'_>> {
    if msg.starts_with(b"libudev\0") {
        return None;
    }
    let mut parts = msg.split(|&b| b == 0);
    let header = std::str::from_utf8(parts.next()?).ok()?;
    let (head_action, head_path) = header.split_once('@')?;
    let mut ev = Uevent {
        action: action(head_action),
        subsystem: "",
        devname: "",
        devpath: head_path,
    };
    for part in parts {
        let Ok(field) = std::str::from_utf8(part) else {
            continue;
        };
        let Some((k, v)) = field.split_once('=') else {
            continue;
        };
        match k {
            "ACTION" => ev.action = action(v),
            "SUBSYSTEM" => ev.subsystem = v,
            "DEVNAME" => ev.devname = v,
            "DEVPATH" => ev.devpath = v,
            _ => {}
        }
    }
    Some(ev)
}

fn action(s: &str) -> Action {
    match s {
        "add" => Action::Add,
        "remove" => Action::Remove,
        _ => Action::Other,
    }
}

/// The message the kernel sends for a node coming (`add`) or going (`remove`), as simulators
/// and tests write it.
pub fn message(action: &str, subsystem: &str, devname: &str, devpath: &str) -> Vec<u8> {
    let mut m = Vec::with_capacity(160);
    for part in [
        format!("{action}@{devpath}"),
        format!("ACTION={action}"),
        format!("DEVPATH={devpath}"),
        format!("SUBSYSTEM={subsystem}"),
        format!("DEVNAME={devname}"),
        "SEQNUM=1".to_string(),
    ] {
        m.extend_from_slice(part.as_bytes());
        m.push(0);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kernel_message_parses() {
        let m = b"add@/devices/x/0003:046D:C626.0001/hidraw/hidraw0\0ACTION=add\0\
                  DEVPATH=/devices/x/0003:046D:C626.0001/hidraw/hidraw0\0SUBSYSTEM=hidraw\0\
                  MAJOR=241\0MINOR=0\0DEVNAME=hidraw0\0SEQNUM=3021\0";
        let ev = parse(m).unwrap();
        assert_eq!(ev.action, Action::Add);
        assert_eq!(ev.subsystem, "hidraw");
        assert_eq!(ev.devname, "hidraw0");
        assert!(ev.devpath.ends_with("hidraw/hidraw0"));
        assert!(ev.is_device_node());
    }

    #[test]
    fn input_events_only_count_for_event_nodes() {
        let m = message(
            "remove",
            "input",
            "input/event4",
            "/devices/x/input/input9/event4",
        );
        let ev = parse(&m).unwrap();
        assert_eq!(ev.action, Action::Remove);
        assert!(ev.is_device_node());
        let m = message("add", "input", "", "/devices/x/input/input9");
        assert!(!parse(&m).unwrap().is_device_node());
        let m = message("add", "input", "input/js0", "/devices/x/input/input9/js0");
        assert!(!parse(&m).unwrap().is_device_node());
        let m = message("bind", "usb", "", "/devices/x");
        assert_eq!(parse(&m).unwrap().action, Action::Other);
    }

    #[test]
    fn udev_rebroadcasts_and_garbage_are_ignored() {
        assert!(parse(b"libudev\0\xfe\xed\xca\xfe....").is_none());
        assert!(parse(b"").is_none());
        assert!(parse(b"no at sign\0ACTION=add\0").is_none());
        assert!(parse(&[0xff, b'@', 0]).is_none());
        // Bad fields are skipped, the rest still counts.
        let ev = parse(b"add@/d\0\xff\xfe\0SUBSYSTEM=hidraw\0junk\0DEVNAME=hidraw1\0").unwrap();
        assert_eq!((ev.subsystem, ev.devname), ("hidraw", "hidraw1"));
    }
}
