//! Tokens of the model language, each with its span. Never fails: a character the language does not
//! have becomes a diagnostic and is skipped.

use canopener_eds::diag::Span;

use crate::diagnostics::{MbtCode, MbtDiagnostic, diag};

/// One token.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Tok {
    /// A name or keyword (`model`, `nmt`, `PreOperational`, `_`).
    Ident(String),
    /// `$NODEID`.
    NodeId,
    /// A number; a duration literal (`100ms`) is in microseconds and flagged.
    Int { value: i64, duration: bool },
    /// A quoted string, unescaped.
    Str(String),
    /// Punctuation or an operator, as written (`->`, `:=`, `..`, `&&`, ...).
    Punct(&'static str),
    /// The end of the input.
    Eof,
}

/// A token and where it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Token {
    pub(crate) tok: Tok,
    pub(crate) span: Span,
}

/// Longest first, so that `..` wins over `.` and `:=` over `:`.
const PUNCTS: &[&str] = &[
    "->", ":=", "..", "==", "!=", "<=", ">=", "&&", "||", "<<", ">>", "(", ")", "{", "}", ",", ":", "=", ".",
    "@", "+", "-", "*", "/", "%", "&", "|", "^", "<", ">", "!",
];

/// Splits `text` into tokens (the last is [`Tok::Eof`]) and reports what it could not read.
pub(crate) fn lex(text: &str) -> (Vec<Token>, Vec<MbtDiagnostic>) {
    let mut lexer = Lexer {
        chars: text.chars().collect(),
        pos: 0,
        line: 1,
        column: 1,
        tokens: Vec::new(),
        diagnostics: Vec::new(),
    };
    lexer.run();
    (lexer.tokens, lexer.diagnostics)
}

struct Lexer {
    chars: Vec<char>,
    pos: usize,
    line: u32,
    column: u32,
    tokens: Vec<Token>,
    diagnostics: Vec<MbtDiagnostic>,
}

impl Lexer {
    fn peek(&self, ahead: usize) -> Option<char> {
        self.chars.get(self.pos + ahead).copied()
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.chars.get(self.pos).copied()?;
        self.pos += 1;
        if c == '\n' {
            self.line += 1;
            self.column = 1;
        } else {
            self.column += 1;
        }
        Some(c)
    }

    fn push(&mut self, tok: Tok, line: u32, column: u32, len: usize) {
        let len = u32::try_from(len).unwrap_or(u32::MAX);
        self.tokens.push(Token {
            tok,
            span: Span::new(line, column, len),
        });
    }

    fn run(&mut self) {
        while let Some(c) = self.peek(0) {
            let (line, column, start) = (self.line, self.column, self.pos);
            if c.is_whitespace() {
                self.bump();
            } else if c == '/' && self.peek(1) == Some('/') {
                while self.peek(0).is_some_and(|c| c != '\n') {
                    self.bump();
                }
            } else if c == '"' {
                self.string(line, column);
            } else if c.is_ascii_digit() {
                self.number(line, column);
            } else if c == '$' {
                self.bump();
                let word = self.word();
                if word == "NODEID" {
                    self.push(Tok::NodeId, line, column, self.pos - start);
                } else {
                    self.diagnostics.push(diag(
                        MbtCode::Syntax,
                        Span::new(line, column, 1 + word.chars().count() as u32),
                        format!("`${word}` is not defined; the only `$` name is `$NODEID`"),
                    ));
                }
            } else if c.is_alphabetic() || c == '_' {
                let word = self.word();
                self.push(Tok::Ident(word), line, column, self.pos - start);
            } else if let Some(p) = PUNCTS.iter().find(|p| self.starts_with(p)) {
                for _ in 0..p.len() {
                    self.bump();
                }
                self.push(Tok::Punct(p), line, column, p.len());
            } else {
                self.bump();
                self.diagnostics.push(diag(
                    MbtCode::Syntax,
                    Span::new(line, column, 1),
                    format!("unexpected character `{c}`"),
                ));
            }
        }
        self.push(Tok::Eof, self.line, self.column, 0);
    }

    fn starts_with(&self, p: &str) -> bool {
        p.chars().enumerate().all(|(i, c)| self.peek(i) == Some(c))
    }

    fn word(&mut self) -> String {
        let mut word = String::new();
        while let Some(c) = self.peek(0).filter(|c| c.is_alphanumeric() || *c == '_') {
            word.push(c);
            self.bump();
        }
        word
    }

    fn string(&mut self, line: u32, column: u32) {
        let start = self.pos;
        self.bump();
        let mut text = String::new();
        loop {
            match self.peek(0) {
                None | Some('\n') => {
                    self.diagnostics.push(diag(
                        MbtCode::UnterminatedString,
                        Span::new(line, column, (self.pos - start) as u32),
                        "this string is not closed before the end of the line",
                    ));
                    break;
                }
                Some('"') => {
                    self.bump();
                    break;
                }
                Some('\\') if self.peek(1).is_some_and(|c| c == '"' || c == '\\') => {
                    self.bump();
                    text.extend(self.bump());
                }
                Some(c) => {
                    text.push(c);
                    self.bump();
                }
            }
        }
        self.push(Tok::Str(text), line, column, self.pos - start);
    }

    /// Decimal or `0x` hexadecimal, `_` as separator, and an optional unit right after the digits:
    /// `us`, `ms`, `s`, `min` make a duration in microseconds.
    fn number(&mut self, line: u32, column: u32) {
        let start = self.pos;
        let hex = self.peek(0) == Some('0') && matches!(self.peek(1), Some('x' | 'X'));
        if hex {
            self.bump();
            self.bump();
        }
        let mut digits = String::new();
        while let Some(c) = self
            .peek(0)
            .filter(|c| c.is_ascii_hexdigit() && (hex || c.is_ascii_digit()) || *c == '_')
        {
            if c != '_' {
                digits.push(c);
            }
            self.bump();
        }
        let unit = if hex { String::new() } else { self.word() };
        let span = Span::new(line, column, (self.pos - start) as u32);
        let parsed = if hex {
            i64::from_str_radix(&digits, 16)
        } else {
            digits.parse::<i64>()
        };
        let Ok(value) = parsed else {
            self.diagnostics.push(diag(
                MbtCode::BadNumber,
                span,
                format!("`{}` is not a number that fits 63 bits", self.text(start)),
            ));
            self.push(
                Tok::Int {
                    value: 0,
                    duration: false,
                },
                line,
                column,
                self.pos - start,
            );
            return;
        };
        let scale = match unit.as_str() {
            "" => None,
            "us" => Some(1),
            "ms" => Some(1_000),
            "s" => Some(1_000_000),
            "min" => Some(60_000_000),
            other => {
                self.diagnostics.push(diag(
                    MbtCode::BadNumber,
                    span,
                    format!(
                        "unknown unit `{other}` after a number; durations are written 10us, 100ms, 2s or 1min"
                    ),
                ));
                Some(1)
            }
        };
        let tok = match scale {
            None => Tok::Int {
                value,
                duration: false,
            },
            Some(scale) => match value.checked_mul(scale) {
                Some(value) => Tok::Int {
                    value,
                    duration: true,
                },
                None => {
                    self.diagnostics.push(diag(
                        MbtCode::BadNumber,
                        span,
                        format!("the duration `{}` is too long", self.text(start)),
                    ));
                    Tok::Int {
                        value: 0,
                        duration: true,
                    }
                }
            },
        };
        self.push(tok, line, column, self.pos - start);
    }

    fn text(&self, start: usize) -> String {
        self.chars
            .get(start..self.pos)
            .unwrap_or_default()
            .iter()
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(text: &str) -> Vec<Tok> {
        let (tokens, diagnostics) = lex(text);
        assert!(diagnostics.is_empty(), "{diagnostics:?}");
        tokens.into_iter().map(|t| t.tok).collect()
    }

    #[test]
    fn numbers_durations_and_operators() {
        assert_eq!(
            toks("0x7_05 100ms 2s 1_000 a..b $NODEID := -> <= !="),
            vec![
                Tok::Int {
                    value: 0x705,
                    duration: false
                },
                Tok::Int {
                    value: 100_000,
                    duration: true
                },
                Tok::Int {
                    value: 2_000_000,
                    duration: true
                },
                Tok::Int {
                    value: 1000,
                    duration: false
                },
                Tok::Ident("a".into()),
                Tok::Punct(".."),
                Tok::Ident("b".into()),
                Tok::NodeId,
                Tok::Punct(":="),
                Tok::Punct("->"),
                Tok::Punct("<="),
                Tok::Punct("!="),
                Tok::Eof,
            ]
        );
        assert_eq!(
            toks("0..10"),
            vec![
                Tok::Int {
                    value: 0,
                    duration: false
                },
                Tok::Punct(".."),
                Tok::Int {
                    value: 10,
                    duration: false
                },
                Tok::Eof
            ]
        );
    }

    #[test]
    fn spans_are_lines_and_columns() {
        let (tokens, _) = lex("model nmt\n  title \"x\" // c\n");
        let spans: Vec<(u32, u32, u32)> = tokens
            .iter()
            .map(|t| (t.span.line, t.span.column, t.span.len))
            .collect();
        assert_eq!(spans, vec![(1, 1, 5), (1, 7, 3), (2, 3, 5), (2, 9, 3), (3, 1, 0)]);
    }

    #[test]
    fn bad_input_is_reported_not_fatal() {
        let (tokens, diagnostics) = lex("a # \"open\n99999999999999999999 5 parsecs $FOO");
        let codes: Vec<&str> = diagnostics.iter().map(|d| d.code.as_str()).collect();
        assert_eq!(codes, ["M001", "M002", "M003", "M001"]);
        assert_eq!(diagnostics[0].span, Span::new(1, 3, 1));
        assert!(matches!(tokens.last().map(|t| &t.tok), Some(Tok::Eof)));
        let (_, d) = lex("5parsecs");
        assert!(d[0].message.contains("unknown unit `parsecs`"), "{d:?}");
    }
}
