//! Delta debugging (Zeller's ddmin) over a failing run's inputs: the shortest input script that
//! still fails, and 1-minimal (no single input can be left out).
//!
//! The test is the caller's: on a device it re-runs the script (replay) and says whether the verdict
//! is still `fail`. Runs are deterministic on virtual time; on a real bus a flaky device can make
//! the result longer than necessary, never wrong (every kept script did fail).

/// The smallest sub-sequence of `items` found for which `fails` holds, with the number of tests
/// run. `fails(items)` is assumed; the result is 1-minimal: removing any single item makes it pass.
pub fn ddmin<T: Clone>(items: &[T], mut fails: impl FnMut(&[T]) -> bool) -> (Vec<T>, usize) {
    let mut current = items.to_vec();
    let mut runs = 0;
    let mut n = 2usize;
    while current.len() >= 2 {
        let chunk = current.len().div_ceil(n);
        let mut reduced = false;
        // Complements first: dropping one chunk at a time.
        for start in (0..current.len()).step_by(chunk) {
            let end = (start + chunk).min(current.len());
            let complement: Vec<T> = current
                .iter()
                .enumerate()
                .filter(|(i, _)| !(start..end).contains(i))
                .map(|(_, item)| item.clone())
                .collect();
            runs += 1;
            if fails(&complement) {
                current = complement;
                n = (n - 1).max(2);
                reduced = true;
                break;
            }
        }
        if !reduced {
            if n >= current.len() {
                break;
            }
            n = (n * 2).min(current.len());
        }
    }
    // ddmin at granularity 1 already tried every single removal; an empty script is tried too.
    if current.len() == 1 {
        runs += 1;
        if fails(&[]) {
            current.clear();
        }
    }
    (current, runs)
}

/// Whether no single item of `items` can be removed with `fails` still holding.
pub fn is_one_minimal<T: Clone>(items: &[T], mut fails: impl FnMut(&[T]) -> bool) -> bool {
    (0..items.len()).all(|i| {
        let mut fewer = items.to_vec();
        fewer.remove(i);
        !fails(&fewer)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn finds_the_two_inputs_that_matter() {
        // Fails when it contains a 3 and, later, a 7: the known answer is [3, 7].
        let fails = |s: &[u32]| {
            s.iter()
                .position(|x| *x == 3)
                .is_some_and(|i| s[i..].contains(&7))
        };
        let input = [1, 5, 3, 9, 2, 8, 7, 4, 6, 0];
        let (short, runs) = ddmin(&input, fails);
        assert_eq!(short, [3, 7]);
        assert!(runs < 40, "{runs} runs");
        assert!(is_one_minimal(&short, fails));
    }

    #[test]
    fn a_failure_that_needs_nothing_shrinks_to_nothing() {
        assert_eq!(ddmin(&[1, 2, 3], |_| true).0, Vec::<i32>::new());
    }

    proptest! {
        #[test]
        fn results_still_fail_and_are_one_minimal(
            noise in proptest::collection::vec(0u8..6, 0..30),
            need in proptest::collection::vec(0u8..6, 1..4),
            gaps in proptest::collection::vec(0usize..10, 3),
        ) {
            // Fails when `need` is a subsequence of the input. The input is built to contain it (rejecting
            // inputs that lack it would exhaust proptest's reject budget at high case counts).
            let fails = |s: &[u8]| {
                let mut it = s.iter();
                need.iter().all(|n| it.any(|x| x == n))
            };
            let mut input = noise;
            let mut at = 0;
            for (n, gap) in need.iter().zip(&gaps) {
                at = (at + gap).min(input.len());
                input.insert(at, *n);
                at += 1;
            }
            prop_assert!(fails(&input));
            let (short, _) = ddmin(&input, fails);
            prop_assert!(fails(&short));
            prop_assert!(is_one_minimal(&short, fails));
            prop_assert_eq!(short, need.clone());
        }
    }
}
