//! What the performance tests are judged by and how often they repeat: the user's criteria
//! (`--criteria FILE`, [`criteria`]) and the repetitions. It sits below every suite because a test's
//! [`Ctx`](crate::context::Ctx) carries it.

pub mod criteria;

pub use criteria::Criteria;

/// How often a response time is measured unless `--repetitions` says otherwise (the thesis's 1000,
/// §4.2.2).
pub const DEFAULT_REPETITIONS: usize = 1000;

/// What the performance tests are judged by and how often they repeat.
#[derive(Debug, Clone, PartialEq)]
pub struct Performance {
    /// The pass criteria.
    pub criteria: Criteria,
    /// How many samples of each response time (SDO, RTR, LSS per service); the boot-up time takes at
    /// most `cia313::BOOT_UPS` of them, since each costs a reset.
    pub repetitions: usize,
}

impl Performance {
    /// The documented defaults: [`Criteria::DEFAULT`] and [`DEFAULT_REPETITIONS`].
    pub const DEFAULT: Performance = Performance {
        criteria: Criteria::DEFAULT,
        repetitions: DEFAULT_REPETITIONS,
    };
}

impl Default for Performance {
    fn default() -> Performance {
        Performance::DEFAULT
    }
}
