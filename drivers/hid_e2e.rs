//! End to end for the pad drivers: each keyword's device on a fake tree, its simulator
//! plugged in, reports through a real server socket to a client's remotes. The client must
//! see exactly the decoder's values (whose arithmetic the families' own tests check against
//! the C++ formulas), then the unplug reported, then the device served again after a replug.

use std::cell::RefCell;
use std::rc::Rc;

use super::hid_pad::{PadDecoder, PadState};
use crate::devices::base::TEXT_MESSAGE;
use crate::devices::text::decode_text;
use crate::devices::ServerDevice;
use crate::hid::rig::Rig;
use crate::hid::DeviceHub;
use crate::{AnalogRemote, ButtonRemote, Connection, DialRemote, Error, SenderFilter};

/// A device builder: keyword's device named `name` on the rig's server and hub.
pub(crate) type Build =
    Box<dyn Fn(&str, &Connection, &DeviceHub) -> Result<Box<dyn ServerDevice>, Error>>;

/// One keyword to check.
pub(crate) struct Entry<D: PadDecoder> {
    pub keyword: &'static str,
    pub vendor: u16,
    pub product: u16,
    pub interface: i32,
    pub channels: usize,
    pub buttons: usize,
    pub build: Build,
    /// A fresh decoder, the reference for the values.
    pub decoder: D,
    /// Reports to send.
    pub samples: Vec<Vec<u8>>,
}

#[derive(Default)]
struct Seen {
    analog: Option<Vec<f64>>,
    analog_reports: usize,
    buttons: Vec<i32>,
    dials: Vec<(usize, f64)>,
    texts: Vec<String>,
}

/// Runs every entry on one rig (see the module documentation).
pub(crate) fn check<D: PadDecoder>(entries: Vec<Entry<D>>) {
    let mut rig = Rig::new();
    rig.connect();
    let mut listeners = Vec::new();
    for (i, mut e) in entries.into_iter().enumerate() {
        let name = format!("Dev{i}");
        let n = 10 + i as u32;
        let dev = (e.build)(&name, &rig.server, &rig.hub).unwrap();
        rig.devices.push(dev);
        let seen = Rc::new(RefCell::new(Seen {
            buttons: vec![0; e.buttons],
            ..Seen::default()
        }));
        let ar = AnalogRemote::on_connection(&name, &rig.client).unwrap();
        let br = ButtonRemote::on_connection(&name, &rig.client).unwrap();
        let dr = DialRemote::on_connection(&name, &rig.client).unwrap();
        let s = seen.clone();
        ar.on_report(move |r| {
            let mut s = s.borrow_mut();
            s.analog = Some(r.channels().to_vec());
            s.analog_reports += 1;
        });
        let s = seen.clone();
        br.on_change(move |c| {
            if let Some(b) = s.borrow_mut().buttons.get_mut(c.button) {
                *b = c.state.raw();
            }
        });
        let s = seen.clone();
        dr.on_update(move |u| s.borrow_mut().dials.push((u.dial, u.change)));
        let sender = rig.client.register_sender(&name).unwrap();
        let text = rig.client.register_type(TEXT_MESSAGE).unwrap();
        let s = seen.clone();
        rig.client
            .register_handler(text, SenderFilter::Only(sender), move |m| {
                if let Some((_, _, t)) = decode_text(m.payload) {
                    s.borrow_mut().texts.push(t.to_owned());
                }
            });
        rig.until("the device says it is waiting", |_| {
            seen.borrow()
                .texts
                .iter()
                .any(|t| t.contains("waiting for"))
        });
        let first = rig.plug(n, e.vendor, e.product, e.interface, e.keyword);
        let mut end = rig.accept(&first);
        let mut listener = Some(first);
        let mut want = PadState::default();
        let mut want_dials = Vec::new();
        for round in 0..2 {
            let samples = if round == 0 {
                e.samples.clone()
            } else {
                e.samples[..1].to_vec()
            };
            for r in &samples {
                end.send_report(r).unwrap();
                if e.decoder.decode(r, &mut want).is_err() {
                    continue;
                }
                for d in 0..want.dial.len() {
                    if want.dial[d] != 0.0 {
                        want_dials.push((d, want.dial[d]));
                        want.dial[d] = 0.0;
                    }
                }
                let (channels, buttons) = (e.channels, e.buttons);
                let want_c = want.channel[..channels].to_vec();
                let want_b: Vec<i32> = want.button[..buttons]
                    .iter()
                    .map(|b| i32::from(*b))
                    .collect();
                let want_d = want_dials.clone();
                rig.until(&format!("{}: report {r:02x?}", e.keyword), |_| {
                    let s = seen.borrow();
                    let analog_ok = channels == 0
                        || s.analog.as_deref() == Some(&want_c[..])
                        || (s.analog.is_none() && want_c.iter().all(|v| *v == 0.0));
                    analog_ok && s.buttons == want_b && s.dials == want_d
                });
            }
            if round == 1 {
                break;
            }
            // Unplug: the server says so; replug: it serves the device again.
            drop(end);
            rig.unplug(n);
            rig.until(&format!("{}: unplug reported", e.keyword), |_| {
                seen.borrow().texts.iter().any(|t| t.contains("unplugged"))
            });
            drop(listener.take());
            let listener = rig.plug(n, e.vendor, e.product, e.interface, e.keyword);
            end = rig.accept(&listener);
            rig.until(&format!("{}: back reported", e.keyword), |_| {
                seen.borrow().texts.iter().any(|t| t.contains("is back"))
            });
            // A replugged device forgets its dial positions; the values stay until the
            // device sends new ones.
            e.decoder.opened(&mut want, &mut crate::hid::HidOps::new());
            listeners.push(listener);
        }
        let _keep = (ar, br, dr);
    }
}
