//! The `ObjFlags` of an object description (CiA 306-1 §4.6.3.2, Table 8).
//!
//! The flags tell configuration tools what to skip; the device itself ignores them, and so does
//! this dictionary, which only stores them for the layers that write DCFs or scan devices.

use std::fmt;
use std::ops::BitOr;

/// An entry's `ObjFlags` word. Every bit pattern is kept, including the reserved bits 2–31, so a
/// dictionary built from a file can be written back without losing anything.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ObjFlags(pub u32);

impl ObjFlags {
    /// No flag set, the value when an EDS omits `ObjFlags`.
    pub const NONE: ObjFlags = ObjFlags(0);
    /// Bit 0: a configuration tool does not write the entry when it downloads a DCF.
    pub const REFUSE_WRITE_ON_DOWNLOAD: ObjFlags = ObjFlags(0x0000_0001);
    /// Bit 1: a configuration tool does not read the entry when it scans the device.
    pub const REFUSE_READ_ON_SCAN: ObjFlags = ObjFlags(0x0000_0002);

    /// Whether every bit of `flags` is set in `self`.
    pub const fn contains(self, flags: ObjFlags) -> bool {
        self.0 & flags.0 == flags.0
    }

    /// The bits CiA 306-1 reserves (2–31) that are set; non-zero means the source departs from the
    /// specification.
    pub const fn reserved_bits(self) -> u32 {
        self.0 & !(ObjFlags::REFUSE_WRITE_ON_DOWNLOAD.0 | ObjFlags::REFUSE_READ_ON_SCAN.0)
    }
}

impl BitOr for ObjFlags {
    type Output = ObjFlags;

    fn bitor(self, rhs: ObjFlags) -> ObjFlags {
        ObjFlags(self.0 | rhs.0)
    }
}

impl fmt::Debug for ObjFlags {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ObjFlags({:#X})", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn combines_and_tests_flags() {
        let both = ObjFlags::REFUSE_WRITE_ON_DOWNLOAD | ObjFlags::REFUSE_READ_ON_SCAN;
        assert_eq!(both, ObjFlags(3));
        assert!(both.contains(ObjFlags::REFUSE_READ_ON_SCAN));
        assert!(!ObjFlags::REFUSE_WRITE_ON_DOWNLOAD.contains(ObjFlags::REFUSE_READ_ON_SCAN));
        assert!(ObjFlags::NONE.contains(ObjFlags::NONE));
        assert_eq!(ObjFlags::default(), ObjFlags::NONE);
    }

    #[test]
    fn reports_reserved_bits_and_keeps_them() {
        assert_eq!(ObjFlags(3).reserved_bits(), 0);
        assert_eq!(ObjFlags(0x8000_0005).reserved_bits(), 0x8000_0004);
        assert_eq!(format!("{:?}", ObjFlags(0x8000_0005)), "ObjFlags(0x80000005)");
    }
}
