//! Why an element is not a valid command or message.

/// How much of an element an error message quotes; elements from a peer can be long garbage.
const QUOTED_ELEMENT_MAX: usize = 80;

/// Why an element could not be parsed. Every variant names the element (shortened when long) and
/// the field that was wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CommandError {
    /// The text does not start with `<` and end with `>`.
    #[error("`{element}` is not a socketcand element: it must start with '<' and end with '>'")]
    NotAnElement {
        /// The offending text.
        element: String,
    },
    /// The element has nothing between its brackets.
    #[error("socketcand element `{element}` is empty: expected a command such as `< open can0 >`")]
    Empty {
        /// The offending element.
        element: String,
    },
    /// The element ends before a required field.
    #[error("socketcand element `{element}` ends before its {field}")]
    MissingField {
        /// The offending element.
        element: String,
        /// The field that is missing, e.g. "can id".
        field: &'static str,
    },
    /// The element has more fields than its command takes.
    #[error("socketcand element `{element}` has unexpected trailing `{junk}`; remove it")]
    TrailingJunk {
        /// The offending element.
        element: String,
        /// The extra text.
        junk: String,
    },
    /// The identifier is not hexadecimal or too long.
    #[error("socketcand element `{element}`: can id `{token}` is not 1 to 8 hex digits")]
    IdNotHex {
        /// The offending element.
        element: String,
        /// The identifier token.
        token: String,
    },
    /// A server frame identifier that is neither 3 nor 8 digits, which python-can would misread.
    #[error(
        "socketcand element `{element}`: frame id `{token}` must have exactly 3 (standard) or 8 \
         (extended) hex digits"
    )]
    IdWidth {
        /// The offending element.
        element: String,
        /// The identifier token.
        token: String,
    },
    /// A standard identifier above 0x7FF.
    #[error(
        "socketcand element `{element}`: standard can id `{token}` is larger than 7FF; an extended id \
         must be written with exactly 8 hex digits"
    )]
    StandardIdTooLarge {
        /// The offending element.
        element: String,
        /// The identifier token.
        token: String,
    },
    /// An extended identifier above 0x1FFFFFFF.
    #[error("socketcand element `{element}`: extended can id `{token}` is larger than 1FFFFFFF")]
    ExtendedIdTooLarge {
        /// The offending element.
        element: String,
        /// The identifier token.
        token: String,
    },
    /// The length field is not a decimal number from 0 to 8.
    #[error("socketcand element `{element}`: length `{token}` is not a decimal number from 0 to 8")]
    BadLength {
        /// The offending element.
        element: String,
        /// The length token.
        token: String,
    },
    /// A data byte of a `send` command is not one or two hex digits.
    #[error("socketcand element `{element}`: data byte `{token}` is not 1 or 2 hex digits")]
    BadDataByte {
        /// The offending element.
        element: String,
        /// The byte token.
        token: String,
    },
    /// The number of data bytes differs from the declared length (and is not python-can's remote
    /// frame shape, which has no bytes at all).
    #[error("socketcand element `{element}` declares {declared} data bytes but carries {given}")]
    ByteCountMismatch {
        /// The offending element.
        element: String,
        /// The declared length.
        declared: u8,
        /// The number of byte tokens present.
        given: usize,
    },
    /// Frame data from the server is not contiguous hex of at most 8 bytes.
    #[error(
        "socketcand element `{element}`: frame data `{token}` is not contiguous hex of at most 8 bytes \
         (an even number of hex digits, at most 16)"
    )]
    BadFrameData {
        /// The offending element.
        element: String,
        /// The data token.
        token: String,
    },
    /// The timestamp is not `SECS.USECS`.
    #[error(
        "socketcand element `{element}`: timestamp `{token}` is not SECS.USECS (decimal seconds, a dot and \
         1 to 9 fraction digits, at most year 2554)"
    )]
    BadTimestamp {
        /// The offending element.
        element: String,
        /// The timestamp token.
        token: String,
    },
    /// The error class of an error frame is not hexadecimal.
    #[error("socketcand element `{element}`: error class `{token}` is not 1 to 8 hex digits")]
    BadErrorClass {
        /// The offending element.
        element: String,
        /// The class token.
        token: String,
    },
    /// An `open` names a bus that socketcand would refuse.
    #[error(
        "socketcand element `{element}`: bus name `{name}` is invalid: use 1 to 16 characters from \
         A-Z, a-z, 0-9, '_', '.' and '-'"
    )]
    InvalidBusName {
        /// The offending element.
        element: String,
        /// The rejected name.
        name: String,
    },
}

/// The element as quoted in an error: whole when short, otherwise its start and a marker.
pub(crate) fn quote(element: &str) -> String {
    if element.len() <= QUOTED_ELEMENT_MAX {
        return element.to_owned();
    }
    let mut end = QUOTED_ELEMENT_MAX;
    while !element.is_char_boundary(end) {
        end -= 1;
    }
    format!(
        "{}… ({} bytes)",
        element.get(..end).unwrap_or_default(),
        element.len()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_elements_are_shortened_on_a_char_boundary() {
        let long = format!("< {} >", "é".repeat(100));
        let quoted = quote(&long);
        assert!(quoted.len() < 100, "{quoted}");
        assert!(quoted.ends_with(&format!("({} bytes)", long.len())));
        assert_eq!(quote("< ok >"), "< ok >");
    }

    #[test]
    fn messages_name_element_and_field_in_lowercase_without_period() {
        let error = CommandError::BadLength {
            element: "< send 123 9 >".into(),
            token: "9".into(),
        };
        let text = error.to_string();
        assert_eq!(
            text,
            "socketcand element `< send 123 9 >`: length `9` is not a decimal number from 0 to 8"
        );
        assert!(!text.ends_with('.'));
    }
}
