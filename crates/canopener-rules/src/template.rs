//! Message templates: text with `{CEL expression}` insertions, `{{` and `}}` for literal braces.

use cel::Value;

use crate::expr::Compiled;

/// A compiled template.
#[derive(Debug)]
pub(crate) struct Template {
    pub(crate) parts: Vec<Part>,
}

/// Literal text or an expression whose value is inserted.
#[derive(Debug)]
pub(crate) enum Part {
    Text(String),
    Expr(Compiled),
}

/// A template split before compiling; `offset` is the byte offset of the expression in the template.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Piece {
    Text(String),
    Expr { offset: usize, source: String },
}

/// Splits a template; the error is the byte offset of the problem and what it is.
///
/// An expression ends at the `}` that closes its `{`: braces inside it (map literals) nest, and
/// braces inside its quoted strings do not count.
pub(crate) fn split(template: &str) -> Result<Vec<Piece>, (usize, String)> {
    let mut pieces = Vec::new();
    let mut text = String::new();
    let mut chars = template.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        match c {
            '{' if chars.peek().is_some_and(|(_, n)| *n == '{') => {
                chars.next();
                text.push('{');
            }
            '}' if chars.peek().is_some_and(|(_, n)| *n == '}') => {
                chars.next();
                text.push('}');
            }
            '}' => return Err((i, "`}` without a `{` before it".to_owned())),
            '{' => {
                let start = i + 1;
                let mut depth = 1usize;
                let mut quote: Option<char> = None;
                let mut escaped = false;
                let mut end = None;
                for (j, d) in chars.by_ref() {
                    if let Some(q) = quote {
                        if escaped {
                            escaped = false;
                        } else if d == '\\' {
                            escaped = true;
                        } else if d == q {
                            quote = None;
                        }
                        continue;
                    }
                    match d {
                        '\'' | '"' => quote = Some(d),
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = Some(j);
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                let Some(end) = end else {
                    return Err((i, "`{` is never closed".to_owned()));
                };
                let source = template.get(start..end).unwrap_or_default();
                if source.trim().is_empty() {
                    return Err((i, "`{}` has no expression in it".to_owned()));
                }
                if !text.is_empty() {
                    pieces.push(Piece::Text(std::mem::take(&mut text)));
                }
                pieces.push(Piece::Expr {
                    offset: start,
                    source: source.to_owned(),
                });
            }
            other => text.push(other),
        }
    }
    if !text.is_empty() {
        pieces.push(Piece::Text(text));
    }
    Ok(pieces)
}

/// A value as a message shows it: strings bare at the top level, quoted inside lists and maps.
pub(crate) fn show(value: &Value) -> String {
    match value {
        Value::String(s) => s.as_str().to_owned(),
        other => show_nested(other),
    }
}

fn show_nested(value: &Value) -> String {
    match value {
        Value::String(s) => format!("{:?}", s.as_str()),
        Value::Int(i) => i.to_string(),
        Value::UInt(u) => u.to_string(),
        Value::Float(f) => f.to_string(),
        Value::Bool(b) => b.to_string(),
        Value::Null => "null".to_owned(),
        Value::List(items) => format!(
            "[{}]",
            items.iter().map(show_nested).collect::<Vec<_>>().join(", ")
        ),
        Value::Map(m) => {
            let mut entries: Vec<String> = m
                .map
                .iter()
                .map(|(k, v)| format!("{}: {}", show_nested(&Value::from(k)), show_nested(v)))
                .collect();
            entries.sort();
            format!("{{{}}}", entries.join(", "))
        }
        other => format!("{other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;

    fn expr(offset: usize, source: &str) -> Piece {
        Piece::Expr {
            offset,
            source: source.to_owned(),
        }
    }

    #[test]
    fn splits_text_and_expressions() {
        assert_eq!(
            split("Name '{item.name}' has {size(x)} blanks"),
            Ok(vec![
                Piece::Text("Name '".to_owned()),
                expr(7, "item.name"),
                Piece::Text("' has ".to_owned()),
                expr(24, "size(x)"),
                Piece::Text(" blanks".to_owned()),
            ])
        );
        assert_eq!(split(""), Ok(vec![]));
        assert_eq!(split("{a}"), Ok(vec![expr(1, "a")]));
    }

    #[test]
    fn braces_nest_and_escape() {
        assert_eq!(
            split("{{literal}}"),
            Ok(vec![Piece::Text("{literal}".to_owned())])
        );
        assert_eq!(split("{ {'a': 1}.a }"), Ok(vec![expr(1, " {'a': 1}.a ")]));
        assert_eq!(split("{'}' + \"{\"}"), Ok(vec![expr(1, "'}' + \"{\"")]));
        assert_eq!(split("{'it\\'s}'}"), Ok(vec![expr(1, "'it\\'s}'")]));
    }

    #[test]
    fn malformed_templates_say_where() {
        assert_eq!(split("ab {item.name"), Err((3, "`{` is never closed".to_owned())));
        assert_eq!(split("ab }"), Err((3, "`}` without a `{` before it".to_owned())));
        assert_eq!(
            split("x { }"),
            Err((2, "`{}` has no expression in it".to_owned()))
        );
    }

    #[test]
    fn values_are_shown_plainly() {
        assert_eq!(show(&Value::from("a b")), "a b");
        assert_eq!(show(&Value::Int(-3)), "-3");
        assert_eq!(show(&Value::Null), "null");
        let list = Value::List(Arc::new(vec![Value::from("x"), Value::Int(1), Value::Bool(true)]));
        assert_eq!(show(&list), "[\"x\", 1, true]");
        let map = Value::Map(std::collections::HashMap::from([("k", 2i64)]).into());
        assert_eq!(show(&map), "{\"k\": 2}");
    }
}
