//! Reports built from a descriptor's fields, and the real descriptors kept as fixtures
//! (`fixtures/*.hex`, each naming its source).

use crate::hid::descriptor::Field;

/// A fixture's bytes (hex pairs; `#` starts a comment).
pub fn hex(text: &str) -> Vec<u8> {
    text.lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .flat_map(str::split_whitespace)
        .map(|t| u8::from_str_radix(t, 16).expect("fixture bytes are hex pairs"))
        .collect()
}

/// Microsoft Xbox Wireless Controller over Bluetooth (a game pad).
pub fn xbox_wireless_controller() -> Vec<u8> {
    hex(include_str!("fixtures/xbox_wireless_controller_bt.hex"))
}

/// FR-TEC Raptor MACH 2 (a flight stick).
pub fn raptor_mach2() -> Vec<u8> {
    hex(include_str!("fixtures/frtec_raptor_mach2.hex"))
}

/// 3Dconnexion SpaceNavigator (a six-axis SpaceMouse).
pub fn spacenavigator() -> Vec<u8> {
    hex(include_str!("fixtures/spacenavigator.hex"))
}

/// 3Dconnexion SpaceMouse Wireless (six axes in one report).
pub fn spacemouse_wireless() -> Vec<u8> {
    hex(include_str!("fixtures/spacemouse_wireless.hex"))
}

/// Writes `value` into `field`'s bits of `data` (the report after its id byte).
pub fn put(field: &Field, value: i32, data: &mut [u8]) {
    for i in 0..field.bit_size as usize {
        let bit = field.bit_offset as usize + i;
        let on = (value >> i) & 1 != 0;
        if on {
            data[bit / 8] |= 1 << (bit % 8);
        } else {
            data[bit / 8] &= !(1 << (bit % 8));
        }
    }
}

/// A report of `report_id` (`bytes` long after the id, which is included when the device
/// uses ids) with `values` written into their fields.
pub fn report(uses_ids: bool, report_id: u8, bytes: usize, values: &[(&Field, i32)]) -> Vec<u8> {
    let mut data = vec![0u8; bytes];
    for (f, v) in values {
        assert_eq!(f.report_id, report_id, "a field of another report");
        put(f, *v, &mut data);
    }
    if uses_ids {
        let mut r = vec![report_id];
        r.extend_from_slice(&data);
        r
    } else {
        data
    }
}
