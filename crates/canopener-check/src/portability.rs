//! The portability lint (`T` codes): where python canopen 2.4.1, Lely (dcfchk 2.4.0 and its C
//! loader), canopen-host 0.6.1 and CANopenEditor will misread, reject or crash on a file.
//!
//! No other checker has this. Each finding says what every affected tool does with the file, using
//! only behaviour the quirk matrix observed or the parsers' sources show (`canopen-tools-survey.md`
//! §1c, `eds-format-and-checks.md` §11). A `T` finding may sit on the same line as a `P` or `C`
//! finding: those say what CiA 306 requires, this one what the tools will do. Nothing is reported
//! that every tool reads the same way.

mod checks;
mod info;
mod objects;
mod sections;
mod text;
mod tools;
mod values;

use crate::check_info::CheckInfo;
use crate::context::Context;
use crate::finding::Finding;

/// The checks of this group.
pub const CHECKS: &[CheckInfo] = &[
    checks::COMPACT_UNNAMED,
    checks::COMPACT_NAMES_GAP,
    checks::LEADING_ZERO,
    checks::NODEID_SUFFIX,
    checks::NODEID_COMPOUND,
    checks::DUMMY_USAGE_PARTIAL,
    checks::DUPLICATE_SECTION,
    checks::DUPLICATE_KEY,
    checks::SUB_CASE,
    checks::ORPHAN_SUB,
    checks::VAR_MISSING_KEY,
    checks::HEX_SUFFIX,
    checks::LISTED_MISSING,
    checks::UNLISTED_OBJECT,
    checks::UNSIGNED_OVERFLOW,
    checks::ACCESS_TYPE_TOKEN,
    checks::REAL_BIT_PATTERN,
    checks::REAL_DECIMAL,
    checks::SIGNED_LIMIT_BITS,
    checks::INLINE_COMMENT,
    checks::UTF8_BOM,
    checks::NOT_UTF8,
    checks::DOMAIN_WITHOUT_TYPES,
    checks::CUSTOM_DATA_TYPE,
    checks::DCF_BAUDRATE,
    checks::MISSING_INFO_SECTION,
    checks::SUB_BEFORE_PARENT,
    checks::INFO_BOOLEAN,
    checks::COMPACT_PDO_NO_MODULES,
    checks::COMPACT_VALUES_IGNORED,
    checks::COMPACT_LIMITS,
    checks::SECTION_DIGITS,
    checks::ARRAY_WITHOUT_SUB_NUMBER,
    checks::OBJECT_LINKS,
    checks::TPDO_WITHOUT_MAPPING,
    checks::VENDOR_NUMBER,
    checks::KEY_CASE,
    checks::SECTION_CASE,
    checks::UNKNOWN_KEYS,
    checks::STRING_BACKSLASH,
];

/// Runs the portability lint.
pub fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let kinds = cx.section_kinds();
    text::run(cx, kinds, out);
    sections::run(cx, kinds, out);
    info::run(cx, out);
    objects::run(cx, out);
    tools::for_each_site(cx, kinds, |site| {
        sections::site(cx, site, out);
        objects::site(cx, site, out);
        values::site(cx, site, out);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_numbered_in_order_and_unique() {
        for (i, check) in CHECKS.iter().enumerate() {
            assert_eq!(check.code, format!("T{:03}", i + 1));
            assert_eq!(check.group, crate::check_info::Group::Portability);
            assert!(
                check.explanation.lines().all(|l| !l.starts_with('#')),
                "{}",
                check.code
            );
        }
        let mut slugs: Vec<&str> = CHECKS.iter().map(|c| c.slug).collect();
        slugs.sort_unstable();
        slugs.dedup();
        assert_eq!(slugs.len(), CHECKS.len());
    }
}
