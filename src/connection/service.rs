//! The class of service of a message: how it travels.

use crate::wire::class;

/// How a message travels: [`RELIABLE`](Self::RELIABLE) goes over TCP (arrives, in order);
/// anything else over UDP once the peer announced a UDP port (may be lost, never waits
/// behind a lost packet). The other bits are hints C++ defines and no transport acts on.
///
/// Methods that take a class accept a `ServiceClass` or the raw `u32` mask of
/// [`wire::class`](crate::wire::class) (`impl Into<ServiceClass>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ServiceClass(u32);

impl ServiceClass {
    /// Must arrive, in order: TCP. Commands, requests and replies.
    pub const RELIABLE: ServiceClass = ServiceClass(class::RELIABLE);
    /// Hint only.
    pub const FIXED_LATENCY: ServiceClass = ServiceClass(class::FIXED_LATENCY);
    /// Prefer fast, may drop: UDP. Streams of reports where only the newest matters.
    pub const LOW_LATENCY: ServiceClass = ServiceClass(class::LOW_LATENCY);
    /// Hint only.
    pub const FIXED_THROUGHPUT: ServiceClass = ServiceClass(class::FIXED_THROUGHPUT);
    /// Hint only.
    pub const HIGH_THROUGHPUT: ServiceClass = ServiceClass(class::HIGH_THROUGHPUT);

    /// The raw mask as it goes on the wire.
    pub const fn bits(self) -> u32 {
        self.0
    }

    /// A class from a raw mask (any bits; unknown ones are carried as they are).
    pub const fn from_bits(bits: u32) -> ServiceClass {
        ServiceClass(bits)
    }

    /// True when the message goes over TCP.
    pub const fn is_reliable(self) -> bool {
        self.0 & class::RELIABLE != 0
    }
}

impl From<u32> for ServiceClass {
    fn from(bits: u32) -> Self {
        ServiceClass(bits)
    }
}

impl From<ServiceClass> for u32 {
    fn from(c: ServiceClass) -> Self {
        c.0
    }
}

impl std::ops::BitOr for ServiceClass {
    type Output = ServiceClass;
    fn bitor(self, rhs: ServiceClass) -> ServiceClass {
        ServiceClass(self.0 | rhs.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_masks_and_typed_classes_agree() {
        assert_eq!(ServiceClass::from(class::RELIABLE), ServiceClass::RELIABLE);
        assert!(ServiceClass::RELIABLE.is_reliable());
        assert!(!ServiceClass::LOW_LATENCY.is_reliable());
        let both = ServiceClass::RELIABLE | ServiceClass::LOW_LATENCY;
        assert_eq!(both.bits(), class::RELIABLE | class::LOW_LATENCY);
        assert!(both.is_reliable());
    }
}
