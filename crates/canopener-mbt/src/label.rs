//! Labels: a gate and its field values, printed the way CADP prints LNT gate offers
//! (`NMT !0x81 !0x05`), and read back from that text.

use std::fmt::Write as _;

use crate::model::Model;

/// A gate with concrete field values; `None` is a field the model leaves open (`_`), which only
/// happens in labels of an explored state space.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Label {
    /// The gate (index into [`Model::gates`]).
    pub gate: usize,
    /// One value per field, in the gate's field order.
    pub values: Vec<Option<i64>>,
}

impl Label {
    /// A label with every field known.
    pub fn concrete(gate: usize, values: &[i64]) -> Label {
        Label {
            gate,
            values: values.iter().copied().map(Some).collect(),
        }
    }

    /// The field values, if every field is known.
    pub fn known_values(&self) -> Option<Vec<i64>> {
        self.values.iter().copied().collect()
    }
}

impl Model {
    /// The label as text: `GATE !v1 !v2`, values in hexadecimal with the width of their field,
    /// open fields as `_`.
    pub fn label_text(&self, label: &Label) -> String {
        let gate = self.gate_at(label.gate);
        let mut text = gate.name.clone();
        for (field, value) in gate.fields.iter().zip(&label.values) {
            match value {
                None => text.push_str(" !_"),
                Some(v) => {
                    let width = usize::from(field.size) * 2;
                    let _ = write!(text, " !0x{:0width$X}", *v as u64);
                }
            }
        }
        text
    }
}

/// A label read from text: the gate's name and its value tokens.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LabelText {
    /// The gate name (the first word).
    pub gate: String,
    /// The offers after it, without their `!`.
    pub values: Vec<Offer>,
}

/// One value of a label read from text.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Offer {
    /// A number, decimal or `0x` hexadecimal.
    Number(i64),
    /// `_`: any value.
    Any,
    /// Anything else, compared as text (CADP labels may carry any value).
    Text(String),
}

impl LabelText {
    /// Reads `GATE !v1 !v2` (the `!` may be left out, values are separated by blanks).
    pub fn parse(text: &str) -> Option<LabelText> {
        let mut words = text.split_whitespace();
        let gate = words.next()?.to_owned();
        let values = words
            .map(|w| {
                let w = w.strip_prefix('!').unwrap_or(w);
                if w == "_" {
                    return Offer::Any;
                }
                let number = match w.strip_prefix("0x").or_else(|| w.strip_prefix("0X")) {
                    Some(hex) => i64::from_str_radix(hex, 16).ok(),
                    None => w.parse().ok(),
                };
                number.map_or_else(|| Offer::Text(w.to_owned()), Offer::Number)
            })
            .collect();
        Some(LabelText { gate, values })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn label_text_reads_hex_decimal_and_wildcards() {
        let read = LabelText::parse("SDO_TX !0x43 !4120 _ !lock(x)").unwrap();
        assert_eq!(read.gate, "SDO_TX");
        assert_eq!(
            read.values,
            [
                Offer::Number(0x43),
                Offer::Number(4120),
                Offer::Any,
                Offer::Text("lock(x)".into())
            ]
        );
        assert_eq!(LabelText::parse("  "), None);
    }
}
