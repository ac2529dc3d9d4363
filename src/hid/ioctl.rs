//! The hidraw ioctls (`linux/hidraw.h`) and the one descriptor adoption the sockets need: the
//! only `unsafe` code of the HID layer, each call a thin wrapper checked by the kernel.

#![allow(unsafe_code)]

use std::io;
use std::os::fd::{FromRawFd, OwnedFd, RawFd};

/// Largest report descriptor the kernel hands out (`HID_MAX_DESCRIPTOR_SIZE`).
pub const MAX_DESCRIPTOR: usize = 4096;

#[repr(C)]
struct RawDescriptor {
    size: u32,
    value: [u8; MAX_DESCRIPTOR],
}

#[repr(C)]
#[derive(Default)]
struct RawInfo {
    bustype: u32,
    vendor: i16,
    product: i16,
}

/// The generated wrappers (private: the safe functions below are the interface).
mod raw {
    use super::{RawDescriptor, RawInfo};
    nix::ioctl_read!(hidiocgrdescsize, b'H', 0x01, nix::libc::c_int);
    nix::ioctl_read!(hidiocgrdesc, b'H', 0x02, RawDescriptor);
    nix::ioctl_read!(hidiocgrawinfo, b'H', 0x03, RawInfo);
    nix::ioctl_readwrite_buf!(hidiocsfeature, b'H', 0x06, u8);
    nix::ioctl_readwrite_buf!(hidiocgfeature, b'H', 0x07, u8);
}
use raw::*;

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

/// Takes ownership of a descriptor a system call just returned.
pub(crate) fn own_fd(fd: RawFd) -> OwnedFd {
    // SAFETY: `fd` was just returned by a successful socket/accept call and nothing else owns
    // it.
    unsafe { OwnedFd::from_raw_fd(fd) }
}

/// The report descriptor of an open hidraw node (`HIDIOCGRDESCSIZE`, `HIDIOCGRDESC`).
pub fn report_descriptor(fd: RawFd) -> io::Result<Vec<u8>> {
    let mut size: nix::libc::c_int = 0;
    // SAFETY: the kernel writes one int.
    unsafe { hidiocgrdescsize(fd, &mut size) }.map_err(errno)?;
    let size = (size.max(0) as usize).min(MAX_DESCRIPTOR);
    let mut d = Box::new(RawDescriptor {
        size: size as u32,
        value: [0; MAX_DESCRIPTOR],
    });
    // SAFETY: the kernel fills at most `size` bytes of the fixed-size array.
    unsafe { hidiocgrdesc(fd, &mut *d) }.map_err(errno)?;
    Ok(d.value[..size].to_vec())
}

/// Bus, vendor and product of an open hidraw node (`HIDIOCGRAWINFO`).
pub fn raw_info(fd: RawFd) -> io::Result<(u32, u16, u16)> {
    let mut info = RawInfo::default();
    // SAFETY: the kernel writes one struct of this layout.
    unsafe { hidiocgrawinfo(fd, &mut info) }.map_err(errno)?;
    Ok((info.bustype, info.vendor as u16, info.product as u16))
}

/// Sends a feature report (`HIDIOCSFEATURE`); `report[0]` is the report id (0 if the
/// device has none). Returns the bytes sent.
pub fn set_feature(fd: RawFd, report: &[u8]) -> io::Result<usize> {
    let mut buf = report.to_vec();
    // SAFETY: the kernel reads `buf.len()` bytes (the length is part of the request code).
    let n = unsafe { hidiocsfeature(fd, &mut buf) }.map_err(errno)?;
    Ok(n.max(0) as usize)
}

/// Reads a feature report (`HIDIOCGFEATURE`) into `buf`, whose first byte is the report id
/// asked for. Returns the length the device answered with.
pub fn get_feature(fd: RawFd, buf: &mut [u8]) -> io::Result<usize> {
    // SAFETY: the kernel writes at most `buf.len()` bytes.
    let n = unsafe { hidiocgfeature(fd, buf) }.map_err(errno)?;
    Ok(n.max(0) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::fd::AsRawFd;

    /// On a file that is not a hidraw node every call fails cleanly (the kernel checks the
    /// request), which is what a server sees on a wrong path.
    #[test]
    fn the_ioctls_fail_cleanly_on_other_files() {
        let f = std::fs::File::open("/dev/null").unwrap();
        assert!(report_descriptor(f.as_raw_fd()).is_err());
        assert!(raw_info(f.as_raw_fd()).is_err());
        assert!(set_feature(f.as_raw_fd(), &[0, 1, 2]).is_err());
        assert!(get_feature(f.as_raw_fd(), &mut [0u8; 8]).is_err());
    }

    #[test]
    fn request_codes_match_the_kernel_header() {
        // Values of the C macros on x86-64 and aarch64 (asm-generic ioctl layout).
        use nix::{request_code_read, request_code_readwrite};
        assert_eq!(
            request_code_read!(b'H', 0x01, std::mem::size_of::<nix::libc::c_int>()),
            0x8004_4801
        );
        assert_eq!(
            request_code_read!(b'H', 0x02, std::mem::size_of::<RawDescriptor>()),
            0x9004_4802
        );
        assert_eq!(
            request_code_read!(b'H', 0x03, std::mem::size_of::<RawInfo>()),
            0x8008_4803
        );
        assert_eq!(request_code_readwrite!(b'H', 0x06, 9), 0xC009_4806);
        assert_eq!(request_code_readwrite!(b'H', 0x07, 91), 0xC05B_4807);
    }
}
