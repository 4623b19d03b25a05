//! CAN-IDs a device must refuse for its own COB-IDs (CiA 301, pre-defined connection set: restricted
//! CAN-IDs), shared by every core that accepts COB-ID writes (EMCY, SYNC, TIME, PDO).

/// Whether an 11-bit CAN-ID is one CiA 301 reserves for NMT, SYNC/EMCY/TIME defaults, the default SDO
/// channels, LSS and NMT error control: 000h–07Fh, 101h–180h, 581h–5FFh, 601h–67Fh, 6E0h–6FFh and
/// 701h–7FFh (the set CANopenNode checks and CiA's conformance test expects).
pub fn is_restricted(can_id: u16) -> bool {
    matches!(can_id, 0x000..=0x07F | 0x101..=0x180 | 0x581..=0x5FF | 0x601..=0x67F | 0x6E0..=0x6FF | 0x701..=0x7FF)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_of_every_restricted_range() {
        for id in [
            0x000, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x6FF, 0x701, 0x7FF,
        ] {
            assert!(is_restricted(id), "{id:03X}h must be restricted");
        }
        for id in [0x080, 0x100, 0x181, 0x580, 0x600, 0x680, 0x6DF, 0x700] {
            assert!(!is_restricted(id), "{id:03X}h must be allowed");
        }
    }
}
