//! Lines and columns, counted one way for every file canopener reports on: CiA 306 EDS/DCF text, CiA 311
//! XDD/XDC and GraphML alike, so that a position, the source line shown under it and the line numbers of
//! SARIF, HTML and JSON reports always agree.
//!
//! **The rule.** A line ends at LF, at CR LF, or at a CR that no LF follows. That is how XML reads line
//! breaks (XML 1.0 §2.11 turns CR LF and a lone CR into LF before anything else), and CiA 306 text is
//! read the same way (§4.2 allows LF and CR LF; a lone CR is reported, `P004`, and ends the line as
//! well). Lines and columns are 1-based; a column counts characters (Unicode
//! scalar values), not bytes. A text that ends with a line break has one more, empty, line after it,
//! which is where a position at the very end of the file lies.
//!
//! [`line_end`] and [`ending_at`] are the rule; the EDS syntax layer ([`crate::Document`]) splits its
//! lines with them and [`LineIndex`] answers positions and line texts for any other text.

/// How a line ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LineEnding {
    /// `\n`
    Lf,
    /// `\r\n`
    CrLf,
    /// A bare `\r` (not allowed by CiA 306, seen in old Mac files; a line break in XML).
    Cr,
    /// The last line of a file without a final newline.
    None,
}

impl LineEnding {
    /// The characters of this ending.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Lf => "\n",
            Self::CrLf => "\r\n",
            Self::Cr => "\r",
            Self::None => "",
        }
    }
}

/// The offset of the first CR or LF at or after `from`, or the text length: where the line that
/// contains `from` ends.
pub fn line_end(bytes: &[u8], from: usize) -> usize {
    const ONES: u64 = u64::from_ne_bytes([0x01; 8]);
    const HIGHS: u64 = u64::from_ne_bytes([0x80; 8]);
    const LFS: u64 = u64::from_ne_bytes([b'\n'; 8]);
    const CRS: u64 = u64::from_ne_bytes([b'\r'; 8]);
    // Marks the zero bytes of a word; the lowest mark is exact (borrows only run upwards), which is
    // all the search needs.
    let zero_bytes = |v: u64| v.wrapping_sub(ONES) & !v & HIGHS;
    let mut i = from;
    // Eight bytes per step: values and comments are long enough for this to beat a byte loop.
    while let Some(word) = bytes.get(i..).and_then(<[u8]>::first_chunk::<8>) {
        let word = u64::from_le_bytes(*word);
        let found = zero_bytes(word ^ LFS) | zero_bytes(word ^ CRS);
        if found != 0 {
            // Little-endian: the lowest marked byte is the first in the text.
            return i + (found.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    bytes
        .get(i..)
        .and_then(|rest| rest.iter().position(|&b| b == b'\n' || b == b'\r'))
        .map_or(bytes.len(), |p| i + p)
}

/// The line ending at `end` (an offset [`line_end`] returned) and the offset where the next line
/// starts.
pub fn ending_at(bytes: &[u8], end: usize) -> (LineEnding, usize) {
    match bytes.get(end) {
        Some(b'\n') => (LineEnding::Lf, end + 1),
        Some(b'\r') if bytes.get(end + 1) == Some(&b'\n') => (LineEnding::CrLf, end + 2),
        Some(b'\r') => (LineEnding::Cr, end + 1),
        _ => (LineEnding::None, end),
    }
}

/// Where the lines of a text start, for 1-based positions of byte offsets and the text of a line.
#[derive(Debug, Clone)]
pub struct LineIndex<'a> {
    text: &'a str,
    /// Byte offset of each line's first character; the first is 0.
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    /// Indexes the lines of `text` by the [module's rule](self).
    pub fn new(text: &'a str) -> Self {
        let bytes = text.as_bytes();
        let mut starts = vec![0];
        let mut at = 0;
        loop {
            let end = line_end(bytes, at);
            let (ending, next) = ending_at(bytes, end);
            if ending == LineEnding::None {
                break;
            }
            starts.push(next);
            at = next;
        }
        Self { text, starts }
    }

    /// The number of lines, counting the empty line after a final line break (at least 1).
    pub fn count(&self) -> usize {
        self.starts.len()
    }

    /// The 1-based line and column (in characters) of a byte offset, clamped to the text; an offset
    /// inside a CR LF pair belongs to the line it ends.
    pub fn position(&self, offset: usize) -> (u32, u32) {
        let offset = offset.min(self.text.len());
        let line = self.starts.partition_point(|&s| s <= offset).saturating_sub(1);
        let start = self.starts.get(line).copied().unwrap_or(0);
        let column = self
            .text
            .get(start..offset)
            .map_or(offset - start, |s| s.chars().count());
        (u32_of(line + 1), u32_of(column + 1))
    }

    /// The text of a 1-based line, without its line ending; `None` past the last line.
    pub fn line(&self, number: u32) -> Option<&'a str> {
        let index = usize::try_from(number).ok()?.checked_sub(1)?;
        let start = *self.starts.get(index)?;
        let end = line_end(self.text.as_bytes(), start);
        self.text.get(start..end)
    }

    /// The position, by this module's rule, of a row and column that an XML parser counting only LF
    /// as a line break reported (roxmltree's `TextPos`: rows split at LF, columns in characters after
    /// the last LF), so a parser's error lies where every other position of the file does.
    pub fn position_of_lf_counted(&self, row: u32, column: u32) -> (u32, u32) {
        let bytes = self.text.as_bytes();
        let mut start = 0;
        for _ in 1..row {
            match bytes
                .get(start..)
                .and_then(|rest| rest.iter().position(|&b| b == b'\n'))
            {
                Some(lf) => start += lf + 1,
                None => break,
            }
        }
        let skip = usize::try_from(column.saturating_sub(1)).unwrap_or(usize::MAX);
        let offset = self.text.get(start..).map_or(start, |rest| {
            rest.char_indices()
                .nth(skip)
                .map_or(self.text.len(), |(i, _)| start + i)
        });
        self.position(offset)
    }
}

fn u32_of(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn lf_cr_lf_and_a_lone_cr_each_end_one_line() {
        let text = "a\nbé\r\nc\rd";
        let index = LineIndex::new(text);
        assert_eq!(index.count(), 4);
        let lines: Vec<&str> = (1..=5).filter_map(|n| index.line(n)).collect();
        assert_eq!(lines, ["a", "bé", "c", "d"]);
        assert_eq!(index.position(0), (1, 1));
        assert_eq!(index.position(text.find('c').unwrap_or(0)), (3, 1));
        assert_eq!(index.position(text.find('d').unwrap_or(0)), (4, 1));
        // Columns count characters: `é` is two bytes.
        assert_eq!(index.position(text.find('\r').unwrap_or(0)), (2, 3));
        assert_eq!(index.position(usize::MAX), (4, 2));
    }

    #[test]
    fn a_final_line_break_opens_an_empty_last_line() {
        let index = LineIndex::new("x\r\n");
        assert_eq!((index.count(), index.line(2), index.line(3)), (2, Some(""), None));
        assert_eq!(index.position(3), (2, 1));
        let empty = LineIndex::new("");
        assert_eq!((empty.count(), empty.line(1), empty.line(0)), (1, Some(""), None));
    }

    #[test]
    fn positions_counted_by_lf_alone_are_moved_to_the_rule() {
        // roxmltree would say row 2 for `z`: one LF before it; the lone CR makes it line 3.
        let text = "a\rb\nz";
        let index = LineIndex::new(text);
        assert_eq!(index.position_of_lf_counted(2, 1), (3, 1));
        assert_eq!(index.position_of_lf_counted(1, 3), (2, 1));
        assert_eq!(index.position_of_lf_counted(9, 9), (3, 2));
    }

    proptest! {
        /// The index and the splitting the syntax layer does agree on every text: the same lines with
        /// the same texts, and every offset's line is the line that contains it.
        #[test]
        fn the_index_agrees_with_line_end(bytes in proptest::collection::vec(
            prop_oneof![Just(b'\r'), Just(b'\n'), Just(b'a'), Just(b' ')], 0..40)) {
            let text = String::from_utf8(bytes).unwrap_or_default();
            let index = LineIndex::new(&text);
            let (mut split, mut at) = (Vec::new(), 0);
            loop {
                let end = line_end(text.as_bytes(), at);
                split.push(&text[at..end]);
                let (ending, next) = ending_at(text.as_bytes(), end);
                if ending == LineEnding::None { break; }
                at = next;
            }
            let lines: Vec<&str> = (1..=u32::try_from(index.count()).unwrap_or(0))
                .filter_map(|n| index.line(n))
                .collect();
            prop_assert_eq!(&lines, &split);
            for offset in 0..=text.len() {
                let (line, _) = index.position(offset);
                prop_assert!(line >= 1 && line as usize <= index.count());
            }
        }
    }
}
