//! Device payload layouts: one module per device type, each with plain structs
//! that `decode` from and `encode` into byte slices.
//!
//! Every module also names the message types exactly as C++ registers them (`pub const`
//! strings) and, where a device registers several, lists them in C++ registration order in
//! `TYPE_NAMES`.
//!
//! [`clock`] is the exception: this crate's own clock-synchronisation messages, which C++ 07.x
//! peers ignore.
//!
//! Conventions shared by every struct here:
//!
//! * `decode(&[u8]) -> wire::Result<Self>` never panics. Where the C++ remote handler checks the
//!   payload length exactly (and drops the connection otherwise), `decode` does too and says so;
//!   elsewhere it only needs enough bytes and ignores any tail, as C++ does.
//! * `encode(&self, &mut [u8]) -> usize` writes the payload at the start of the slice and returns
//!   its length. The slice must hold at least `LEN` (or `encoded_len()`) bytes; like the other
//!   encoders in [`crate::wire`] it panics otherwise.
//! * Alignment filler words (`pad`) are kept as decoded, so decoding and re-encoding a C++
//!   payload gives back the same bytes.
//! * Nothing allocates: variable-length payloads decode into fixed arrays sized to the C++
//!   limits, or borrow from the input.

use byteorder::{BigEndian, ByteOrder};

use super::{Result, WireError};

/// A fixed-size big-endian field of a payload.
pub(crate) trait Field: Sized + Copy + Default {
    /// Bytes on the wire.
    const SIZE: usize;
    /// Reads the field from the start of `buf` (which holds at least `SIZE` bytes).
    fn read(buf: &[u8]) -> Self;
    /// Writes the field at the start of `buf` (which holds at least `SIZE` bytes).
    fn write(&self, buf: &mut [u8]);
}

macro_rules! scalar_field {
    ($t:ty, $size:expr, $read:ident, $write:ident) => {
        impl Field for $t {
            const SIZE: usize = $size;
            #[inline]
            fn read(buf: &[u8]) -> Self {
                BigEndian::$read(&buf[..$size])
            }
            #[inline]
            fn write(&self, buf: &mut [u8]) {
                BigEndian::$write(&mut buf[..$size], *self)
            }
        }
    };
}

impl Field for u8 {
    const SIZE: usize = 1;
    #[inline]
    fn read(buf: &[u8]) -> Self {
        buf[0]
    }
    #[inline]
    fn write(&self, buf: &mut [u8]) {
        buf[0] = *self;
    }
}

scalar_field!(i16, 2, read_i16, write_i16);
scalar_field!(u16, 2, read_u16, write_u16);
scalar_field!(i32, 4, read_i32, write_i32);
scalar_field!(u32, 4, read_u32, write_u32);
scalar_field!(f32, 4, read_f32, write_f32);
scalar_field!(f64, 8, read_f64, write_f64);

impl<T: Field, const N: usize> Field for [T; N]
where
    [T; N]: Default,
{
    const SIZE: usize = T::SIZE * N;
    fn read(buf: &[u8]) -> Self {
        let mut out = <[T; N]>::default();
        for (i, v) in out.iter_mut().enumerate() {
            *v = T::read(&buf[i * T::SIZE..]);
        }
        out
    }
    fn write(&self, buf: &mut [u8]) {
        for (i, v) in self.iter().enumerate() {
            v.write(&mut buf[i * T::SIZE..]);
        }
    }
}

/// Requires exactly `len` bytes (the C++ remote handlers that check lengths check equality).
pub(crate) fn exact(buf: &[u8], len: usize, what: &'static str) -> Result<()> {
    super::need(buf, len)?;
    if buf.len() != len {
        return Err(WireError::BadValue(what));
    }
    Ok(())
}

/// Requires at least `len` bytes; a longer payload is accepted and its tail ignored.
pub(crate) fn at_least(buf: &[u8], len: usize, _what: &'static str) -> Result<()> {
    super::need(buf, len)
}

/// Reads the `i`-th big-endian `f64` of `buf` (which must hold it).
#[inline]
pub(crate) fn f64_at(buf: &[u8], i: usize) -> f64 {
    BigEndian::read_f64(&buf[i * 8..i * 8 + 8])
}

/// Defines a fixed-layout payload struct: its fields in wire order, `LEN`, `decode`, `encode`.
///
/// `exact` makes `decode` refuse any other length (the C++ remote checks it); `at_least`
/// accepts a longer payload and ignores the tail.
macro_rules! fixed_payload {
    (
        $(#[$sm:meta])*
        pub struct $name:ident : $check:ident {
            $( $(#[$fm:meta])* pub $f:ident : $t:ty ),* $(,)?
        }
    ) => {
        $(#[$sm])*
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct $name {
            $( $(#[$fm])* pub $f: $t, )*
        }

        impl $name {
            /// Payload length in bytes.
            pub const LEN: usize = 0 $( + <$t as $crate::wire::payload::Field>::SIZE )*;

            #[doc = concat!(
                "Decodes the payload. Length rule: `", stringify!($check),
                "` [`", stringify!($name), "::LEN`] bytes",
                " (`exact`: any other length is an error, as in the C++ handler;",
                " `at_least`: extra bytes are ignored)."
            )]
            #[allow(unused_assignments)]
            #[inline]
            pub fn decode(buf: &[u8]) -> $crate::wire::Result<Self> {
                $crate::wire::payload::$check(
                    buf,
                    Self::LEN,
                    concat!(stringify!($name), " payload length"),
                )?;
                // One bounds check for the whole payload: the fields' offsets are constants.
                #[allow(unused_variables)]
                let buf = &buf[..Self::LEN];
                #[allow(unused_mut, unused_variables)]
                let mut off = 0usize;
                $(
                    let $f = <$t as $crate::wire::payload::Field>::read(&buf[off..]);
                    off += <$t as $crate::wire::payload::Field>::SIZE;
                )*
                Ok(Self { $( $f ),* })
            }

            /// Writes the payload at the start of `out` (at least `LEN` bytes); returns `LEN`.
            #[allow(unused_assignments)]
            #[inline]
            pub fn encode(&self, out: &mut [u8]) -> usize {
                #[allow(unused_variables)]
                let out = &mut out[..Self::LEN];
                #[allow(unused_mut, unused_variables)]
                let mut off = 0usize;
                $(
                    $crate::wire::payload::Field::write(&self.$f, &mut out[off..]);
                    off += <$t as $crate::wire::payload::Field>::SIZE;
                )*
                Self::LEN
            }
        }
    };
}

pub mod analog;
pub mod analog_output;
pub mod aux_logger;
pub mod button;
pub mod clock;
pub mod dial;
pub mod fixed_text;
pub mod force;
pub mod forwarder;
pub mod function_generator;
pub mod imager;
pub mod mutex;
pub mod poser;
pub mod redundant;
pub mod shared_object;
pub mod sound;
pub mod text;
pub mod tracker;

#[cfg(test)]
pub(crate) mod test_util {
    /// Round-trips `v` through encode/decode and checks the bytes and the value.
    macro_rules! round_trip {
        ($ty:ty, $v:expr) => {{
            let v: $ty = $v;
            let mut buf = [0u8; 2048];
            let n = v.encode(&mut buf);
            assert_eq!(n, <$ty>::LEN);
            let back = <$ty>::decode(&buf[..n]).unwrap();
            assert_eq!(back, v);
            let mut again = [0u8; 2048];
            assert_eq!(back.encode(&mut again), n);
            assert_eq!(&again[..n], &buf[..n]);
            // Shorter payloads are refused, never a panic.
            for cut in 0..n {
                assert!(<$ty>::decode(&buf[..cut]).is_err());
            }
            buf[..n].to_vec()
        }};
    }
    pub(crate) use round_trip;

    /// Decodes hex text (whitespace ignored) into bytes.
    pub(crate) fn hex(s: &str) -> Vec<u8> {
        let digits: Vec<u8> = s.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
        digits
            .chunks(2)
            .map(|p| u8::from_str_radix(std::str::from_utf8(p).unwrap(), 16).unwrap())
            .collect()
    }
}
