//! The inertial reports and the HDK's decoded from the simulators' bytes against the C++
//! formulas; keep-alives; every keyword end to end.

use std::cell::RefCell;
use std::rc::Rc;

use super::imu::{self, unpack_vector, Imu};
use super::{hdk, model, sim, MODELS};
use crate::drivers::hid_pad::Skip;
use crate::hid::fake::HostRequest;
use crate::hid::rig::Rig;

#[test]
fn vectors_unpack_21_bit_values() {
    for v in [
        [0, 0, 0],
        [1, -1, 2],
        [1_048_575, -1_048_576, 12345],
        [-5, 70000, -900000],
    ] {
        assert_eq!(unpack_vector(&imu::pack_vector(v)), v);
    }
    // A hand-packed vector: x = 1 (bit 43), y = −1 (bits 22-42), z = 3 (bits 1-2).
    let bits: u64 = (1 << 43) | (0x1f_ffff << 22) | (3 << 1);
    assert_eq!(unpack_vector(&bits.to_be_bytes()), [1, -1, 3]);
}

#[test]
fn type_1_reports_every_sample() {
    let r = sim::type_1(
        513,
        2345,
        &[([100, -200, 9810], [1, 2, 3]), ([7, 8, 9], [-1, -2, -3])],
        [1000, -2000, 0],
        62,
    );
    let mut imu = Imu::default();
    let mut seen = Vec::new();
    imu::type_1(&r, &mut imu, |i| seen.push(i.channel)).unwrap();
    assert_eq!(seen.len(), 2);
    assert_eq!(seen[0][0], f64::from(2345u16) * 0.01);
    assert_eq!(seen[0][1], 513.0);
    assert_eq!(
        seen[0][2..8],
        [
            100.0 * 0.0001,
            -200.0 * 0.0001,
            9810.0 * 0.0001,
            0.0001,
            2.0 * 0.0001,
            3.0 * 0.0001
        ]
    );
    assert_eq!(seen[0][8..11], [-1000.0 * 0.0001, 2000.0 * 0.0001, 0.0]);
    assert_eq!(seen[1][5..8], [-0.0001, -2.0 * 0.0001, -3.0 * 0.0001]);
    assert_eq!(
        imu::type_1(&r[..60], &mut imu, |_| {}),
        Err(Skip::Length(60))
    );
}

#[test]
fn dk2_type_11_with_the_device_clock() {
    let r = sim::type_11(
        7,
        3000,
        1_500_000,
        &[
            (([1, 2, 3], [4, 5, 6]), [10, -20, 30]),
            (([0; 3], [0; 3]), [1, 1, 1]),
        ],
    );
    let mut imu = Imu::default();
    let mut seen = Vec::new();
    imu::type_11(&r, &mut imu, |i| seen.push(i.channel)).unwrap();
    assert_eq!(seen.len(), 2);
    assert_eq!(seen[0][11], 1.5);
    assert_eq!(
        seen[0][8..11],
        [10.0 * 0.0001, -20.0 * 0.0001, 30.0 * 0.0001]
    );
    assert_eq!(seen[1][8], 0.0001);
}

#[test]
fn vality_scales() {
    let mut imu = Imu::default();
    imu::vality(&sim::vality([100, -100, 32767], [32767, 0, -1]), &mut imu).unwrap();
    let mss = (1.0 / 32767.0) * 16.0 * 9.807;
    let rs = (1.0 / 32767.0) * 2000.0 * (std::f64::consts::PI / 180.0);
    assert_eq!(
        imu.channel[..6],
        [
            -32767.0 * mss,
            0.0,
            1.0 * mss,
            100.0 * rs,
            -100.0 * rs,
            32767.0 * rs
        ]
    );
    assert_eq!(imu::vality(&[2; 24], &mut imu), Err(Skip::Kind(2)));
    assert_eq!(imu::vality(&[1; 23], &mut imu), Err(Skip::Length(23)));
}

#[test]
fn keep_alive_reports() {
    assert_eq!(imu::dk1_keep_alive(), [0x08, 0, 0, 0x10, 0x27]);
    assert_eq!(imu::dk2_keep_alive(true), [0x11, 0, 0, 0x0b, 0x10, 0x27]);
    assert_eq!(imu::dk2_keep_alive(false)[3], 0x01);
}

#[test]
fn hdk_orientation_velocity_and_status() {
    let r = hdk::decode(&sim::hdk(0x33, 9, [0, 0, 8192, 14189], [0, 0, 512], 32)).unwrap();
    assert_eq!(r.version, 3);
    assert_eq!(r.quat, [0.0, 0.0, 0.5, 14189.0 / 16384.0]);
    assert_eq!(r.status, hdk::STATUS_PORTRAIT);
    // ω = 1 rad/s about z over 1/50 s: exp(0, 0, 0.01) about the same axis as the pose, so
    // the result is the pure rotation.
    let vq = r.vel_quat.unwrap();
    assert!((vq[2] - 0.01f64.sin()).abs() < 1e-12 && (vq[3] - 0.01f64.cos()).abs() < 1e-12);
    assert_eq!(
        hdk::decode(&sim::hdk(0x13, 0, [0, 0, 0, 16384], [0; 3], 16))
            .unwrap()
            .status,
        hdk::STATUS_LANDSCAPE
    );
    assert_eq!(
        hdk::decode(&sim::hdk(0x03, 0, [0, 0, 0, 16384], [0; 3], 16))
            .unwrap()
            .status,
        hdk::STATUS_NO_VIDEO
    );
    let v1 = hdk::decode(&sim::hdk(0x01, 0, [0, 0, 0, 16384], [0; 3], 16)).unwrap();
    assert_eq!((v1.status, v1.vel_quat), (hdk::STATUS_UNKNOWN, None));
    assert_eq!(hdk::decode(&[2; 20]), Err(hdk::Bad::Length(20)));
    assert_eq!(
        hdk::decode(&sim::hdk(0x02, 0, [0; 4], [0; 3], 32)),
        Err(hdk::Bad::V2Length(32))
    );
}

/// Each inertial keyword: the keep-alive on open, every sample to the client, unplug and
/// replug.
#[test]
fn every_inertial_unit_end_to_end() {
    let mut rig = Rig::new();
    rig.connect();
    for (i, m) in MODELS.iter().enumerate() {
        let name = format!("Hmd{i}");
        rig.devices
            .push(super::build(m, &name, &rig.server, &rig.hub).unwrap());
        let ar = crate::AnalogRemote::on_connection(&name, &rig.client).unwrap();
        let got: Rc<RefCell<Vec<Vec<f64>>>> = Rc::default();
        let g = got.clone();
        ar.on_report(move |r| g.borrow_mut().push(r.channels().to_vec()));
        let n = 40 + i as u32;
        for round in 0..2 {
            let l = rig.plug(n, m.vendor, m.product, 0, m.keyword);
            let end = rig.accept(&l);
            let (report, want): (Vec<u8>, Vec<[f64; 12]>) = match m.kind {
                super::Kind::Vality => {
                    let r = sim::vality([round + 1, 2, 3], [4, 5, 6]);
                    let mut imu = Imu::default();
                    imu::vality(&r, &mut imu).unwrap();
                    (r, vec![imu.channel])
                }
                _ => {
                    let r = sim::type_1(
                        round as u16,
                        2000,
                        &[([1, 2, 3], [4, 5, round as i32]), ([7, 8, 9], [10, 11, 12])],
                        [1, 2, 3],
                        64,
                    );
                    let mut imu = Imu::default();
                    let mut want = Vec::new();
                    imu::type_1(&r, &mut imu, |i| want.push(i.channel)).unwrap();
                    (r, want)
                }
            };
            // The Oculus units are sent their keep-alive first.
            if m.keyword.starts_with("vrpn_Oculus") {
                let mut req = None;
                rig.until("keep-alive", |_| {
                    req = end.try_request().unwrap();
                    req.is_some()
                });
                let want_ka = match m.kind {
                    super::Kind::Dk1 => imu::dk1_keep_alive().to_vec(),
                    super::Kind::Dk2 { leds } => imu::dk2_keep_alive(leds).to_vec(),
                    _ => unreachable!(),
                };
                assert_eq!(req, Some(HostRequest::SetFeature(want_ka)));
            }
            got.borrow_mut().clear();
            end.send_report(&report).unwrap();
            let c = m.channels;
            let want: Vec<Vec<f64>> = want.iter().map(|w| w[..c].to_vec()).collect();
            rig.until(&format!("{} samples", m.keyword), |_| *got.borrow() == want);
            drop(end);
            rig.unplug(n);
            rig.run_for(std::time::Duration::from_millis(30));
            drop(l);
        }
        let _ = model(m.keyword).unwrap();
        // The two DK2 keywords want the same device: one at a time.
        rig.devices.clear();
        drop(ar);
    }
}
