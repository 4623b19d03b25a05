//! What a check is: its stable code, severity, group, the clause that justifies it and its
//! explanation page. A leaf: every check module describes itself with these types, and the
//! registry only assembles the descriptions.
//!
//! Codes never change meaning once published. Series:
//! - `P0xx`: found while loading (syntax and model building), see [`canopener_eds::diag::Code`];
//! - `C1xx`…`C9xx`: checks on the loaded file, the hundreds digit naming the group of the check
//!   catalogue (`docs/check-catalogue.md`) (1 = A syntax, 2 = B FileInfo, 3 = C DeviceInfo and
//!   D DummyUsage, 4 = E object lists, 5 = F object sections, 6 = G values, 7 = H CiA 301 semantics,
//!   8 = I DCF and J modules, 9 = K reference profiles);
//! - `T0xx`: portability, how other tools misread the file;
//! - `X0xx`: found while reading CiA 311 XML (`canopener_xdd::XddCode`), `X1xx`: checks only XML
//!   files need (both reported by the XML check pipeline of `canopener-description`).

use std::fmt;

use canopener_eds::Severity;
use serde::Serialize;

/// The group of a check (the groups A-K of `docs/check-catalogue.md`, plus portability and rule packs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Group {
    /// A. Syntax and lexical rules.
    Syntax,
    /// B. `[FileInfo]`.
    FileInfo,
    /// C. `[DeviceInfo]` and its cross-checks.
    DeviceInfo,
    /// D. `[DummyUsage]`.
    DummyUsage,
    /// E. Object lists.
    ObjectLists,
    /// F. Object and sub-object sections.
    Objects,
    /// G. Values.
    Values,
    /// H. CiA 301 semantics.
    Cia301,
    /// I. DCF-specific.
    Dcf,
    /// J. Modular devices.
    Modules,
    /// K. Comparison with reference profiles.
    Profiles,
    /// How python canopen, Lely and CANopenEditor misread the file.
    Portability,
    /// CiA 311 XDD/XDC: what the XML reader found and the checks only XML needs.
    Xml,
    /// A check from a user rule pack.
    Rules,
}

impl Group {
    /// A short name for tables and filters (`syntax`, `file-info`, …).
    pub fn name(self) -> &'static str {
        match self {
            Self::Syntax => "syntax",
            Self::FileInfo => "file-info",
            Self::DeviceInfo => "device-info",
            Self::DummyUsage => "dummy-usage",
            Self::ObjectLists => "object-lists",
            Self::Objects => "objects",
            Self::Values => "values",
            Self::Cia301 => "cia301",
            Self::Dcf => "dcf",
            Self::Modules => "modules",
            Self::Profiles => "profiles",
            Self::Portability => "portability",
            Self::Xml => "xml",
            Self::Rules => "rules",
        }
    }
}

impl fmt::Display for Group {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A built-in check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CheckInfo {
    /// The stable code, e.g. `C301`.
    pub code: &'static str,
    /// A short kebab-case name, e.g. `vendor-number-mismatch`.
    pub slug: &'static str,
    /// The severity findings are reported with (justified in `explanation`).
    pub severity: Severity,
    /// The group.
    pub group: Group,
    /// One line: what the check verifies.
    pub title: &'static str,
    /// The numbers of the catalogue checks (`docs/check-catalogue.md`) this code implements.
    pub reference: &'static [u8],
    /// The specification clause that makes it a finding, e.g. `CiA 306 V1.3 §4.5`.
    pub spec: &'static str,
    /// The explanation page: why it matters, why this severity, how to fix it (plain text,
    /// paragraphs separated by blank lines).
    pub explanation: &'static str,
    /// Whether `canopener eds fix` corrects it.
    pub fixable: bool,
}

impl CheckInfo {
    /// The owned description used by reports (shared with rule-pack checks).
    pub fn describe(&self) -> CheckDescription {
        CheckDescription {
            code: self.code.to_owned(),
            slug: self.slug.to_owned(),
            severity: self.severity,
            group: self.group,
            title: self.title.to_owned(),
            spec: self.spec.to_owned(),
            explanation: self.explanation.to_owned(),
            fixable: self.fixable,
            tags: vec![self.group.name().to_owned()],
            origin: "built-in".to_owned(),
        }
    }
}

/// A check as reports and `eds rules list` show it, built-in or from a rule pack.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CheckDescription {
    /// The stable code or rule id.
    pub code: String,
    /// A short kebab-case name.
    pub slug: String,
    /// The default severity.
    pub severity: Severity,
    /// The group.
    pub group: Group,
    /// One line: what the check verifies.
    pub title: String,
    /// The specification clause (empty for user rules without one).
    pub spec: String,
    /// The explanation page.
    pub explanation: String,
    /// Whether a fix exists.
    pub fixable: bool,
    /// Tags for `--tag` selection (built-ins carry their group name).
    pub tags: Vec<String>,
    /// `built-in` or the path of the rule pack.
    pub origin: String,
}
