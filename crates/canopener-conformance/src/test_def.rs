//! What a test is: its stable id, its references and the function that runs it. Every suite fills
//! these; the registry (`catalogue`, above the suites) only assembles them.

use crate::context::Ctx;
use crate::finding::Outcome;

/// One test.
#[derive(Clone, Copy)]
pub struct TestDef {
    /// The stable id, `cia301.sdo.3`.
    pub id: &'static str,
    /// The suite (`cia301`, `eds`).
    pub suite: &'static str,
    /// The group the human summary counts (`sdo`, `od`, ...).
    pub group: &'static str,
    /// What it checks.
    pub title: &'static str,
    /// The CiA clauses it implements and the CCT cases it covers.
    pub references: &'static [&'static str],
    /// When it applies, as derived from the EDS (the test says `not_applicable` otherwise).
    pub precondition: &'static str,
    /// Tags for `--tag` (`nmt`, `timing`, `writes`, ...).
    pub tags: &'static [&'static str],
    /// The test itself.
    pub run: fn(&mut Ctx<'_, '_>) -> Outcome,
}

impl TestDef {
    /// Whether the test talks to the device (all but the EDS check do).
    pub fn needs_device(&self) -> bool {
        self.group != "eds"
    }
}

impl std::fmt::Debug for TestDef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TestDef").field("id", &self.id).finish()
    }
}
