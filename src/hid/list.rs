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

    // The drivers' own suggestions are checked in `drivers/hid_config_tests.rs`.
    #[test]
    fn every_node_with_the_lines_its_suggesters_give() {
        let t = FakeTree::new();
        t.add_hidraw(0, 0x046d, 0xc626, 0, "A Known Thing", "");
        t.add_hidraw(1, 0x1234, 0x5678, 0, "Some Vendor Thing", "");
        let known: Suggester = |n| (n.name() == "A Known Thing").then(|| "vrpn_Known K0".into());
        let listed = list(&t.tree(), &[known]);
        assert_eq!(listed.len(), 2);
        assert_eq!(listed[0].lines, vec!["vrpn_Known K0".to_string()]);
        assert!(listed[1].lines.is_empty());
        let text = render(&listed);
        assert!(text.starts_with("hidraw0  usb 046d:c626 interface 0  \"A Known Thing\""));
        assert!(text.contains("    vrpn_Known K0\n"));
        assert!(text.contains("    (no driver for it)\n"));
        assert_eq!(render(&[]), "no HID or input devices found\n");
    }
}
