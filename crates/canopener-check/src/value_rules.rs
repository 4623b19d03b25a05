//! The CiA 301 value ranges of the communication objects, from the same rule table `eds check`
//! evaluates (`docs/cia301-value-rules.md`), for a tester that writes values to a device: a value a
//! range does not allow is one the device must refuse (the table's error rows; devices answer
//! 0609 0030h). Only the rows that restrict an entry's own value without conditions on other
//! entries are ranges here; dependencies between objects stay with the file checks.

use std::ops::RangeInclusive;

use canopener_eds::Severity;

use crate::checks::value_rules::table::{self, Cond, Entry, Rule, Subs, Test};

/// One range: the values CiA 301 allows in some entries of a communication object.
#[derive(Debug, Clone, Copy)]
pub struct ValueRange {
    rule: &'static Rule,
    allowed: Allowed,
}

/// The values a row allows: within these ranges, or outside them.
#[derive(Debug, Clone, Copy)]
enum Allowed {
    Within(&'static [(i128, i128)]),
    Outside(&'static [(i128, i128)]),
}

/// Which entries of an object a range is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Entries {
    /// The value of the object itself (a VAR).
    Object,
    /// One sub-index.
    Sub(u8),
    /// Every sub-index in this range.
    Subs(u8, u8),
}

impl ValueRange {
    /// The objects the range applies to (one object, or a range such as 1600h-17FFh).
    pub fn objects(&self) -> RangeInclusive<u16> {
        self.rule.first..=self.rule.last
    }

    /// Which of their entries.
    pub fn entries(&self) -> Entries {
        match self.rule.subs {
            Subs::Object => Entries::Object,
            Subs::One(sub) => Entries::Sub(sub),
            Subs::Range(first, last) => Entries::Subs(first, last),
        }
    }

    /// Whether the range is about `index`:`sub`; `var` says the object is a VAR (its value is
    /// sub-index 0).
    pub fn applies_to(&self, index: u16, sub: u8, var: bool) -> bool {
        self.objects().contains(&index)
            && match self.entries() {
                Entries::Object => var && sub == 0,
                Entries::Sub(s) => !var && s == sub,
                Entries::Subs(first, last) => !var && (first..=last).contains(&sub) && sub != 0xFF,
            }
    }

    /// Whether CiA 301 allows `value` there.
    pub fn allows(&self, value: i128) -> bool {
        let within = |ranges: &[(i128, i128)]| ranges.iter().any(|&(a, b)| (a..=b).contains(&value));
        match self.allowed {
            Allowed::Within(ranges) => within(ranges),
            Allowed::Outside(ranges) => !within(ranges),
        }
    }

    /// The smallest value of `values` (the entry's data type) that the range refuses while a
    /// smaller value of `values` is allowed: a value "too high" for the rule, as a tester writes
    /// it. `None` when every value above the smallest allowed one is allowed.
    pub fn first_refused_above_allowed(&self, values: RangeInclusive<i128>) -> Option<i128> {
        // The candidates are the ends of the rule's ranges, next to which the answer changes.
        let bounds: &[(i128, i128)] = match self.allowed {
            Allowed::Within(ranges) | Allowed::Outside(ranges) => ranges,
        };
        let mut edges: Vec<i128> = bounds
            .iter()
            .flat_map(|&(a, b)| [a, b.saturating_add(1)])
            .chain([*values.start()])
            .filter(|v| values.contains(v))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let lowest_allowed = edges.iter().copied().find(|v| self.allows(*v))?;
        edges
            .into_iter()
            .find(|v| *v > lowest_allowed && !self.allows(*v))
    }

    /// The rule in words.
    pub fn text(&self) -> &'static str {
        self.rule.text
    }

    /// Where it comes from (the reference notes' sections, the CCT case that tests it).
    pub fn source(&self) -> &'static str {
        self.rule.source
    }
}

/// Every range of the table, in object order: the rows of severity error whose only condition is
/// a set of values for the entry itself.
pub fn value_ranges() -> impl Iterator<Item = ValueRange> {
    table::RULES.iter().filter_map(|rule| {
        if rule.severity != Severity::Error || !rule.when.is_empty() {
            return None;
        }
        let allowed = match rule.then {
            [
                Cond {
                    entry: Entry::This,
                    test: Test::In(ranges),
                },
            ] => Allowed::Within(ranges),
            [
                Cond {
                    entry: Entry::This,
                    test: Test::NotIn(ranges),
                },
            ] => Allowed::Outside(ranges),
            _ => return None,
        };
        Some(ValueRange { rule, allowed })
    })
}

/// The ranges that apply to `index`:`sub` (`var`: the object is a VAR).
pub fn ranges_for(index: u16, sub: u8, var: bool) -> impl Iterator<Item = ValueRange> {
    value_ranges().filter(move |r| r.applies_to(index, sub, var))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_history_count_takes_only_zero_and_ff_is_refused() {
        let ranges: Vec<_> = ranges_for(0x1003, 0, false).collect();
        assert_eq!(ranges.len(), 1, "{ranges:?}");
        let count = ranges[0];
        assert!(count.allows(0));
        assert!(!count.allows(0xFF) && !count.allows(1));
        assert_eq!(count.first_refused_above_allowed(0..=255), Some(1));
        assert!(count.source().contains("CCT SDO 10"), "{}", count.source());
        // Not a VAR's value, not another sub-index.
        assert_eq!(ranges_for(0x1003, 1, false).count(), 0);
        assert_eq!(ranges_for(0x1003, 0, true).count(), 0);
    }

    #[test]
    fn reserved_values_refuse_the_first_value_past_the_allowed_ones() {
        // 1019h: 0 and 2..240 allowed; 1 is refused above the allowed 0.
        let counter: Vec<_> = ranges_for(0x1019, 0, true).collect();
        assert_eq!(counter.len(), 1);
        assert_eq!(counter[0].first_refused_above_allowed(0..=255), Some(1));
        assert!(counter[0].allows(240) && !counter[0].allows(241));
        // TPDO SYNC start value: 0..240 allowed, 241 refused.
        let start: Vec<_> = ranges_for(0x1805, 6, false).collect();
        assert_eq!(start.len(), 1);
        assert_eq!(start[0].first_refused_above_allowed(0..=255), Some(241));
        // Mapping counts: 0..40h and FEh/FFh.
        let count: Vec<_> = ranges_for(0x1A00, 0, false).collect();
        assert_eq!(count[0].first_refused_above_allowed(0..=255), Some(0x41));
        // The consumer heartbeat count 1..127 (the lowest allowed value is 1).
        let consumer: Vec<_> = ranges_for(0x1016, 0, false).collect();
        assert_eq!(consumer[0].first_refused_above_allowed(0..=255), Some(128));
    }

    #[test]
    fn rows_with_conditions_or_below_error_are_not_ranges() {
        // The RPDO inhibit time is an info row (no effect, nothing refused).
        assert_eq!(ranges_for(0x1400, 3, false).count(), 0);
        // The SDO client's node-ID applies only when both COB-IDs are valid.
        assert_eq!(ranges_for(0x1280, 3, false).count(), 0);
        assert!(value_ranges().all(|r| !r.text().is_empty() && !r.source().is_empty()));
    }
}
