//! Which entries of the EDS a test may change.

use std::cmp::Ordering;

use canopener_eds::AccessType;
use canopener_od::Number;

use crate::context::Ctx;
use crate::device_model::EntryModel;

/// A writable numeric entry of `size` bytes the tests may change, communication objects first.
pub fn writable_of_size<'m>(ctx: &Ctx<'m, '_>, sizes: &[usize]) -> Option<&'m EntryModel> {
    let candidates = || {
        ctx.model().entries.values().filter(|e| {
            e.writable()
                && e.readable()
                && e.access != Some(AccessType::Wo)
                && e.data_type.is_some_and(|t| t.is_numeric())
                && e.size().is_some_and(|s| sizes.contains(&s))
                && !is_pdo_or_special(e.index)
        })
    };
    // 1017h first: every device has reason to accept it and it changes nothing else.
    candidates()
        .find(|e| e.index == 0x1017)
        .or_else(|| candidates().next())
}

/// Objects whose writing has side effects beyond the value (PDO parameters, store/restore,
/// the error history, SYNC objects (1019h only while 1006h is 0) and EMCY COB-IDs).
pub fn is_pdo_or_special(index: u16) -> bool {
    matches!(
        index,
        0x1400..=0x1BFF | 0x1010 | 0x1011 | 0x1003 | 0x1005 | 0x1006 | 0x1012 | 0x1014 | 0x1019 | 0x1F51
    )
}

/// A value of `entry` other than `current`, as close to it as possible: `current` with bit 0 (else
/// bit 1) of its lowest byte flipped, inside the EDS's LowLimit/HighLimit; `None` for types other
/// than BOOLEAN and the integers, or when neither flip stays inside the limits.
pub fn another_value(entry: &EntryModel, current: &[u8]) -> Option<Vec<u8>> {
    let data_type = entry.data_type.filter(|t| t.is_numeric() && !is_real(*t))?;
    if entry.size() != Some(current.len()) {
        return None;
    }
    [0x01u8, 0x02].into_iter().find_map(|bit| {
        let mut value = current.to_vec();
        *value.first_mut()? ^= bit;
        let number = Number::decode(data_type, &value)?;
        let inside = entry
            .low
            .is_none_or(|low| number.partial_cmp(&low) != Some(Ordering::Less))
            && entry
                .high
                .is_none_or(|high| number.partial_cmp(&high) != Some(Ordering::Greater));
        inside.then_some(value)
    })
}

fn is_real(data_type: canopener_eds::DataType) -> bool {
    matches!(
        data_type.kind(),
        Some(canopener_eds::TypeKind::Real32 | canopener_eds::TypeKind::Real64)
    )
}
