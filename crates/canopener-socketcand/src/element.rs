//! Splitting a TCP byte stream into socketcand elements.
//!
//! socketcand has no line structure: an element is everything from a `<` up to and including the
//! first `>` after it, and elements may follow each other with nothing in between
//! (`< ok >< frame … >`). Bytes outside any element are ignored by socketcand's `receive_command()`
//! (linux-can/socketcand `src/socketcand.c`), and so they are here, but counted, so that a server can
//! tell a garbage-spewing peer from a quiet one.

/// Why the reader could not yield an element.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FramingError {
    /// A `<` was followed by more bytes than the limit without a closing `>`.
    #[error(
        "socketcand element starting with {prefix:?} has no closing '>' within {limit} bytes; \
         the element was discarded and reading resumes at the next '<' (raise the element length \
         limit if the peer really sends elements this long)"
    )]
    ElementTooLong {
        /// The first bytes of the discarded element, for the log.
        prefix: String,
        /// The limit that was exceeded, in bytes including the brackets.
        limit: usize,
    },
    /// A complete element contained bytes that are not UTF-8 (the protocol is pure ASCII).
    #[error(
        "socketcand element {lossy:?} is not valid UTF-8; the protocol is ASCII only, the element was discarded"
    )]
    NotUtf8 {
        /// The element with invalid bytes replaced, for the log.
        lossy: String,
    },
}

/// The smallest element limit the reader accepts; `< hi >` alone needs 6 bytes.
pub const MIN_ELEMENT_LEN: usize = 8;

/// A limit that fits every element python-can and socketcand produce with room to spare: the longest
/// classical frame, `< frame 1FFFFFFF 18446744073.709551 0011223344556677 >`, is 56 bytes and
/// python-can itself discards unterminated input after 200 characters.
pub const DEFAULT_MAX_ELEMENT_LEN: usize = 256;

/// How many bytes of an over-long element are kept in [`FramingError::ElementTooLong`].
const PREFIX_IN_ERROR: usize = 32;

/// Accumulates TCP bytes and yields complete `< … >` elements.
///
/// Feed every chunk read from the socket to [`ElementReader::push`], then call
/// [`ElementReader::next_element`] until it returns `None`. Memory is bounded by the largest chunk
/// pushed plus the element limit: an element that grows past the limit without a `>` is reported as
/// [`FramingError::ElementTooLong`], dropped, and reading resynchronises at the next `<`.
#[derive(Debug, Clone)]
pub struct ElementReader {
    buf: Vec<u8>,
    /// Start of the unread part of `buf`.
    pos: usize,
    max_element_len: usize,
    discarded_bytes: u64,
    elements: u64,
    framing_errors: u64,
}

impl ElementReader {
    /// A reader that accepts elements of up to `max_element_len` bytes, brackets included.
    /// Limits below [`MIN_ELEMENT_LEN`] are raised to it so that the handshake always fits.
    pub fn new(max_element_len: usize) -> ElementReader {
        ElementReader {
            buf: Vec::new(),
            pos: 0,
            max_element_len: max_element_len.max(MIN_ELEMENT_LEN),
            discarded_bytes: 0,
            elements: 0,
            framing_errors: 0,
        }
    }

    /// Appends bytes received from the peer.
    pub fn push(&mut self, bytes: &[u8]) {
        if self.pos == self.buf.len() {
            // Everything before was consumed: reuse the allocation instead of growing it.
            self.buf.clear();
            self.pos = 0;
        }
        self.buf.extend_from_slice(bytes);
    }

    /// The next complete element, including its `<` and `>`, or `None` when more bytes are needed.
    ///
    /// Bytes between elements are discarded and counted in [`ElementReader::discarded_bytes`].
    pub fn next_element(&mut self) -> Option<Result<String, FramingError>> {
        let element = match self.next_element_bytes()? {
            Ok(bytes) => bytes,
            Err(error) => return Some(Err(error)),
        };
        match std::str::from_utf8(element) {
            Ok(text) => {
                let text = text.to_owned();
                self.elements += 1;
                Some(Ok(text))
            }
            Err(_) => {
                let lossy = String::from_utf8_lossy(element).into_owned();
                self.framing_errors += 1;
                Some(Err(FramingError::NotUtf8 { lossy }))
            }
        }
    }

    /// Bytes that were outside any element, or part of a discarded over-long element.
    pub fn discarded_bytes(&self) -> u64 {
        self.discarded_bytes
    }

    /// Elements yielded successfully so far.
    pub fn elements(&self) -> u64 {
        self.elements
    }

    /// Framing errors (over-long or non-UTF-8 elements) reported so far.
    pub fn framing_errors(&self) -> u64 {
        self.framing_errors
    }

    /// Bytes held for an element that is not complete yet.
    pub fn pending_len(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// The element limit in bytes, brackets included.
    pub fn max_element_len(&self) -> usize {
        self.max_element_len
    }

    fn next_element_bytes(&mut self) -> Option<Result<&[u8], FramingError>> {
        // `pos <= buf.len()` holds everywhere: it only advances by lengths measured inside `buf[pos..]`.
        let rest = self.buf.get(self.pos..).unwrap_or_default();
        let Some(start) = rest.iter().position(|&b| b == b'<') else {
            self.discarded_bytes += rest.len() as u64;
            self.buf.clear();
            self.pos = 0;
            return None;
        };
        self.discarded_bytes += start as u64;
        self.pos += start;
        let rest = self.buf.get(self.pos..).unwrap_or_default();
        let window = rest.get(..self.max_element_len).unwrap_or(rest);
        if let Some(end) = window.iter().position(|&b| b == b'>') {
            let begin = self.pos;
            self.pos += end + 1;
            return self.buf.get(begin..self.pos).map(Ok);
        }
        if rest.len() >= self.max_element_len {
            let prefix =
                String::from_utf8_lossy(window.get(..PREFIX_IN_ERROR).unwrap_or(window)).into_owned();
            self.discarded_bytes += self.max_element_len as u64;
            self.pos += self.max_element_len;
            self.framing_errors += 1;
            // Drop the leading `<` so the scan above does not find it again; the remaining bytes of
            // the over-long element are skipped up to the next `<`.
            return Some(Err(FramingError::ElementTooLong {
                prefix,
                limit: self.max_element_len,
            }));
        }
        // Incomplete: keep only the partial element so the buffer never grows beyond the limit.
        self.buf.drain(..self.pos);
        self.pos = 0;
        None
    }
}

impl Default for ElementReader {
    fn default() -> ElementReader {
        ElementReader::new(DEFAULT_MAX_ELEMENT_LEN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain(reader: &mut ElementReader) -> Vec<Result<String, FramingError>> {
        std::iter::from_fn(|| reader.next_element()).collect()
    }

    #[test]
    fn concatenated_elements_are_split() {
        let mut reader = ElementReader::default();
        reader.push(b"< ok >< frame 123 1.000000  >");
        let elements: Vec<_> = drain(&mut reader).into_iter().map(Result::unwrap).collect();
        assert_eq!(elements, ["< ok >", "< frame 123 1.000000  >"]);
        assert_eq!(reader.discarded_bytes(), 0);
        assert_eq!(reader.elements(), 2);
    }

    #[test]
    fn bytes_outside_elements_are_discarded_and_counted() {
        let mut reader = ElementReader::default();
        reader.push(b"xx< hi >\r\n  < ok >zz");
        let elements: Vec<_> = drain(&mut reader).into_iter().map(Result::unwrap).collect();
        assert_eq!(elements, ["< hi >", "< ok >"]);
        assert_eq!(reader.discarded_bytes(), 2 + 4 + 2);
        assert_eq!(reader.pending_len(), 0);
    }

    #[test]
    fn a_split_element_waits_for_its_end() {
        let mut reader = ElementReader::default();
        reader.push(b"< sen");
        assert_eq!(reader.next_element(), None);
        reader.push(b"d 123 0 ");
        assert_eq!(reader.next_element(), None);
        reader.push(b">");
        assert_eq!(reader.next_element(), Some(Ok("< send 123 0 >".to_owned())));
        assert_eq!(reader.next_element(), None);
    }

    #[test]
    fn an_inner_open_bracket_is_content_as_in_socketcand() {
        let mut reader = ElementReader::default();
        reader.push(b"< a < b >");
        assert_eq!(reader.next_element(), Some(Ok("< a < b >".to_owned())));
    }

    #[test]
    fn over_long_element_is_reported_once_and_reading_resyncs_at_next_open_bracket() {
        let mut reader = ElementReader::new(16);
        let mut input = b"<".to_vec();
        input.extend(std::iter::repeat_n(b'a', 100));
        input.extend_from_slice(b"> < ok >");
        reader.push(&input);
        let results = drain(&mut reader);
        assert_eq!(results.len(), 2, "{results:?}");
        assert!(
            matches!(&results[0], Err(FramingError::ElementTooLong { limit: 16, prefix }) if prefix.starts_with("<aaa"))
        );
        assert_eq!(results[1], Ok("< ok >".to_owned()));
        assert_eq!(reader.framing_errors(), 1);
        assert_eq!(reader.discarded_bytes(), 102 + 1);
    }

    #[test]
    fn over_long_element_spread_over_pushes_keeps_memory_bounded() {
        let mut reader = ElementReader::new(32);
        reader.push(b"<");
        let mut errors = 0;
        for _ in 0..1000 {
            reader.push(&[b'x'; 7]);
            for result in drain(&mut reader) {
                assert!(result.is_err());
                errors += 1;
            }
            assert!(reader.pending_len() < 32, "pending {}", reader.pending_len());
        }
        assert_eq!(errors, 1);
        reader.push(b"< echo >");
        assert_eq!(reader.next_element(), Some(Ok("< echo >".to_owned())));
    }

    #[test]
    fn element_of_exactly_the_limit_is_accepted() {
        let mut reader = ElementReader::new(8);
        reader.push(b"<123456>");
        assert_eq!(reader.next_element(), Some(Ok("<123456>".to_owned())));
        reader.push(b"<1234567>");
        assert!(matches!(
            reader.next_element(),
            Some(Err(FramingError::ElementTooLong { .. }))
        ));
    }

    #[test]
    fn tiny_limits_are_raised_so_the_handshake_fits() {
        let mut reader = ElementReader::new(0);
        assert_eq!(reader.max_element_len(), MIN_ELEMENT_LEN);
        reader.push(b"< hi >");
        assert_eq!(reader.next_element(), Some(Ok("< hi >".to_owned())));
    }

    #[test]
    fn non_utf8_element_is_an_error_and_the_next_one_still_arrives() {
        let mut reader = ElementReader::default();
        reader.push(b"< \xff\xfe >< ok >");
        assert!(matches!(
            reader.next_element(),
            Some(Err(FramingError::NotUtf8 { .. }))
        ));
        assert_eq!(reader.next_element(), Some(Ok("< ok >".to_owned())));
    }
}
