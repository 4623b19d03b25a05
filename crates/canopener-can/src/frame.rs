//! Classical CAN frames (ISO 11898-1 data and remote frames).

use std::fmt;

use crate::id::CanId;

/// The most data bytes a classical CAN frame carries.
pub const MAX_CLASSIC_DATA_LEN: usize = 8;

/// Why a frame cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// More than eight data bytes were given for a classical frame.
    #[error("a classical CAN frame carries at most 8 data bytes, got {0}")]
    DataTooLong(usize),
    /// A remote frame was requested with a DLC above 8.
    #[error("a classical CAN remote frame has a DLC of at most 8, got {0}")]
    DlcTooLarge(u8),
}

/// A classical CAN data or remote frame.
///
/// The fields are private so that every `CanFrame` is valid: at most 8 data bytes, a remote frame
/// carries a DLC but no data. CAN FD frames (up to 64 bytes, BRS/ESI flags) will be added as a new
/// format inside this type rather than a second frame type, so code that only reads `id()`, `data()`
/// and `is_remote()` keeps working.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: CanId,
    remote: bool,
    dlc: u8,
    data: [u8; MAX_CLASSIC_DATA_LEN],
}

impl CanFrame {
    /// A data frame carrying `data` (0 to 8 bytes).
    pub fn new(id: impl Into<CanId>, data: &[u8]) -> Result<CanFrame, FrameError> {
        let mut buf = [0; MAX_CLASSIC_DATA_LEN];
        buf.get_mut(..data.len())
            .ok_or(FrameError::DataTooLong(data.len()))?
            .copy_from_slice(data);
        Ok(CanFrame {
            id: id.into(),
            remote: false,
            dlc: data.len() as u8,
            data: buf,
        })
    }

    /// A remote frame requesting `dlc` bytes (0 to 8).
    pub fn remote(id: impl Into<CanId>, dlc: u8) -> Result<CanFrame, FrameError> {
        if usize::from(dlc) > MAX_CLASSIC_DATA_LEN {
            return Err(FrameError::DlcTooLarge(dlc));
        }
        Ok(CanFrame {
            id: id.into(),
            remote: true,
            dlc,
            data: [0; MAX_CLASSIC_DATA_LEN],
        })
    }

    /// The identifier.
    pub const fn id(&self) -> CanId {
        self.id
    }

    /// Whether this is a remote (RTR) frame.
    pub const fn is_remote(&self) -> bool {
        self.remote
    }

    /// The data length code: the number of data bytes, or the requested length of a remote frame.
    pub const fn dlc(&self) -> u8 {
        self.dlc
    }

    /// The data bytes; empty for a remote frame.
    pub fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            // The constructors keep dlc at 8 or below.
            self.data.get(..usize::from(self.dlc)).unwrap_or(&[])
        }
    }

    /// The arbitration bits as one number: the frame with the smaller key wins arbitration.
    /// See [`CanId::arbitration_key`].
    pub const fn arbitration_key(&self) -> u32 {
        self.id.arbitration_key(self.remote)
    }
}

/// The can-utils compact form: `123#DEADBEEF`, `123#` for no data, `123#R` or `123#R5` for remote
/// frames (the DLC is written only when it is not 0).
impl fmt::Display for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}#", self.id)?;
        if self.remote {
            f.write_str("R")?;
            if self.dlc != 0 {
                write!(f, "{}", self.dlc)?;
            }
            return Ok(());
        }
        for byte in self.data() {
            write!(f, "{byte:02X}")?;
        }
        Ok(())
    }
}

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "CanFrame({self})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::id::{ExtendedId, StandardId};

    fn sid(raw: u16) -> StandardId {
        StandardId::new(raw).unwrap()
    }

    #[test]
    fn data_frame_keeps_exactly_its_bytes() {
        let frame = CanFrame::new(sid(0x601), &[0x40, 0x00, 0x10, 0x00]).unwrap();
        assert_eq!(frame.data(), &[0x40, 0x00, 0x10, 0x00]);
        assert_eq!(frame.dlc(), 4);
        assert!(!frame.is_remote());
        assert_eq!(frame.to_string(), "601#40001000");
    }

    #[test]
    fn too_long_data_is_rejected() {
        assert_eq!(CanFrame::new(sid(1), &[0; 9]), Err(FrameError::DataTooLong(9)));
        assert_eq!(CanFrame::remote(sid(1), 9), Err(FrameError::DlcTooLarge(9)));
    }

    #[test]
    fn remote_frame_has_dlc_but_no_data() {
        let frame = CanFrame::remote(sid(0x701), 1).unwrap();
        assert!(frame.data().is_empty());
        assert_eq!(frame.dlc(), 1);
        assert_eq!(frame.to_string(), "701#R1");
        assert_eq!(CanFrame::remote(sid(0x701), 0).unwrap().to_string(), "701#R");
    }

    #[test]
    fn extended_frames_print_eight_digits() {
        let frame = CanFrame::new(ExtendedId::new(0x1AAA_AAAA).unwrap(), &[0x01, 0xF1]).unwrap();
        assert_eq!(frame.to_string(), "1AAAAAAA#01F1");
        assert_eq!(CanFrame::new(sid(0x123), &[]).unwrap().to_string(), "123#");
    }

    #[test]
    fn data_frame_wins_over_remote_frame_of_same_id() {
        let data = CanFrame::new(sid(0x701), &[]).unwrap();
        let remote = CanFrame::remote(sid(0x701), 0).unwrap();
        assert!(data.arbitration_key() < remote.arbitration_key());
    }
}
