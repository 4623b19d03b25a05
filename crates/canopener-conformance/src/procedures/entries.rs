//! Which entries of the EDS a test may change.

use canopener_eds::AccessType;

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
