//! What is plugged in: every hidraw and evdev node sysfs knows, with the `vrpn.cfg` lines that
//! would serve it (`vrpn_server --list-devices`).

use std::fmt::Write as _;

use super::driver::NodeInfo;
use super::sysfs::{self, DeviceTree};

/// A function naming the line that would serve a node, if its family knows the node.
pub type Suggester = fn(&NodeInfo) -> Option<String>;

/// One node and its lines.
#[derive(Clone, Debug)]
pub struct Listed {
    /// The node.
    pub node: NodeInfo,
    /// Lines that would serve it, best first.
    pub lines: Vec<String>,
}

/// Every node of `tree`, hidraw first, each with what `suggesters` propose.
pub fn list(tree: &DeviceTree, suggesters: &[Suggester]) -> Vec<Listed> {
    let nodes = sysfs::enumerate_hidraw(tree)
        .into_iter()
        .map(NodeInfo::Hid)
        .chain(
            sysfs::enumerate_input(tree)
                .into_iter()
                .map(NodeInfo::Input),
        );
    nodes
        .map(|node| {
            let lines = suggesters.iter().filter_map(|s| s(&node)).collect();
            Listed { node, lines }
        })
        .collect()
}

/// The listing as text: one paragraph per node.
pub fn render(listed: &[Listed]) -> String {
    let mut out = String::new();
    if listed.is_empty() {
        out.push_str("no HID or input devices found\n");
    }
    for l in listed {
        let (v, p) = l.node.ids();
        let detail = match &l.node {
            NodeInfo::Hid(h) => {
                let iface = h
                    .interface
                    .map(|i| format!(" interface {i}"))
                    .unwrap_or_default();
                format!("{} {v:04x}:{p:04x}{iface}", h.bus.label())
            }
            NodeInfo::Input(i) => format!("{} {v:04x}:{p:04x}", i.bus.label()),
        };
        let _ = writeln!(
            out,
            "{}  {detail}  \"{}\"  {}",
            l.node.node(),
            l.node.name(),
            l.node.devnode().display()
        );
        if l.lines.is_empty() {
            out.push_str("    (no driver for it)\n");
        }
        for line in &l.lines {
            let _ = writeln!(out, "    {line}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hid::fake::FakeTree;

    #[test]
    fn every_node_with_the_lines_that_serve_it() {
        let t = FakeTree::new();
        t.add_hidraw(0, 0x046d, 0xc626, 0, "3Dconnexion SpaceNavigator", "");
        t.set_report_descriptor(0, &crate::drivers::hid_generic::sim::spacenavigator());
        t.add_hidraw(1, 0x1234, 0x5678, 0, "Some Vendor Thing", "");
        t.add_input(
            2,
            "USB Optical Mouse",
            0x046d,
            0xc077,
            "17",
            "70000 0 0 0 0",
            "103",
            "",
        );
        t.add_input(
            3,
            "AT Translated Set 2 keyboard",
            1,
            1,
            "120013",
            "3ff0000",
            "",
            "",
        );
        let listed = list(&t.tree(), crate::drivers::SUGGESTERS);
        assert_eq!(listed.len(), 4);
        assert_eq!(
            listed[0].lines,
            vec![
                "vrpn_3DConnexion_Navigator SpaceMouse0".to_string(),
                "vrpn_HID_Generic Device0 046d:c626 0".to_string()
            ]
        );
        assert!(listed[1].lines.is_empty());
        assert_eq!(
            listed[2].lines,
            vec!["vrpn_DevInput Mouse0 \"USB Optical Mouse\" relative".to_string()]
        );
        assert_eq!(
            listed[3].lines,
            vec![
                "vrpn_DevInput Keyboard0 \"AT Translated Set 2 keyboard\" keyboard 255".to_string()
            ]
        );
        let text = render(&listed);
        assert!(
            text.starts_with("hidraw0  usb 046d:c626 interface 0  \"3Dconnexion SpaceNavigator\"")
        );
        assert!(text.contains("    (no driver for it)\n"));
        // Every suggested line is one the server accepts.
        for l in listed.iter().flat_map(|l| l.lines.iter()) {
            crate::server::config::parse_str(&format!("{l}\n"), "suggested").unwrap();
        }
        assert_eq!(render(&[]), "no HID or input devices found\n");
    }
}
