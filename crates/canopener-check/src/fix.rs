//! Safe fixes: line edits that correct a finding and leave every other line byte-identical.
//!
//! A [`Fix`] is planned against one [`Document`] (it names lines and sections by their index in it)
//! and applied with [`apply`]. Built-in checks plan fixes in [`plan`]; rule packs build their own
//! `Fix` values with the same edits.

use canopener_eds::Document;

/// One correction, made of line edits, with what it does in words.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fix {
    /// The code of the finding it corrects.
    pub code: String,
    /// What it does, naming section, key, old and new value (e.g. `[1018] SubNumber: 4 -> 5`).
    pub description: String,
    /// True when the fix changes what the file says about the device (a default value, a name),
    /// not just how it is written; such fixes are always reported as such.
    pub changes_meaning: bool,
    /// The edits, applied together or not at all.
    pub edits: Vec<Edit>,
}

/// A line edit against the document the fix was planned on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Edit {
    /// Replace the value of the entry on this line (index into [`Document::lines`]), keeping the key
    /// and whatever surrounds the value as written.
    SetValue {
        /// The entry line.
        line: usize,
        /// The new value.
        value: String,
    },
    /// Replace a whole line's content (its line ending is kept).
    ReplaceLine {
        /// The line.
        line: usize,
        /// The new content.
        content: String,
    },
    /// Delete a line.
    DeleteLine {
        /// The line.
        line: usize,
    },
    /// Add `key=value` at the end of a section (index into [`Document::sections`]).
    AppendEntry {
        /// The section.
        section: usize,
        /// The key.
        key: String,
        /// The value.
        value: String,
    },
    /// Add whole lines at the end of the file (e.g. a missing section).
    AppendLines {
        /// The lines, without line endings.
        lines: Vec<String>,
    },
}

#[allow(dead_code)]
fn _document(_: &Document) {}
