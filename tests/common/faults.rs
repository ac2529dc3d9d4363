//! The fault steps the serial drivers' end-to-end tests repeat, for a device whose simulator
//! streams on its own: garbage between records, silence that is normal (no reset), and
//! unplugging. `count(client, from)` is how many records the client heard from its log index
//! `from` on.
#![allow(dead_code)]

use std::time::Duration;

use vrpn::sim::rig::{Client, ServerProcess};
use vrpn::sim::{DeviceModel, SimulatedDevice};

/// Puts `junk` between records, waits until it went out and `more` records came after it,
/// and for the driver's "skipped" text.
pub fn garbage_costs_nothing<M: DeviceModel + 'static>(
    sim: &SimulatedDevice<M>,
    client: &Client,
    server: &ServerProcess,
    junk: &[&[u8]],
    count: impl Fn(&Client, usize) -> usize,
    more: usize,
) {
    sim.inject_between_records(junk);
    client.wait_until(Duration::from_secs(5), "the garbage sent", server, |_| {
        sim.injected() == junk.len()
    });
    let have = count(client, 0);
    client.wait_until(
        Duration::from_secs(5),
        "records after garbage",
        server,
        |c| count(c, 0) >= have + more,
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), server);
}

/// Three seconds of silence, normal for the device: no text; then `more` records.
pub fn silence_is_normal<M: DeviceModel + 'static>(
    sim: &SimulatedDevice<M>,
    client: &Client,
    server: &ServerProcess,
    count: impl Fn(&Client, usize) -> usize,
    more: usize,
) {
    let from = client.len();
    sim.set_mute(true);
    client.pump_until(Duration::from_secs(3), |_| false);
    assert_eq!(client.texts_from(from), Vec::<String>::new());
    sim.set_mute(false);
    client.wait_until(
        Duration::from_secs(5),
        "records after silence",
        server,
        |c| count(c, from) >= more,
    );
}

/// Unplugs the device: the failure is reported, the port reopened when it is back, and
/// `more` records follow.
pub fn unplugged_and_reopened<M: DeviceModel + 'static>(
    sim: &SimulatedDevice<M>,
    client: &Client,
    server: &ServerProcess,
    count: impl Fn(&Client, usize) -> usize,
    more: usize,
) {
    let from = client.len();
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), server);
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(8),
        "records after plugging back",
        server,
        |c| count(c, from) >= more,
    );
    client.wait_text(from, "is open again", Duration::from_secs(1), server);
}
