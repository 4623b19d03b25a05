//! Compiled expressions: names resolved to slots of the state vector, fields of the label being
//! taken, constants folded. Every value is an `i64`; conditions are 0 or 1.

use std::fmt;

/// A compiled expression.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum CExpr {
    /// A constant (parameters and constants are folded into these).
    Const(i64),
    /// A slot of the state vector (a variable).
    Slot(usize),
    /// A field of the label the transition takes.
    Field(usize),
    /// Whether the location slot holds one of these location numbers.
    At(usize, Vec<i64>),
    /// `!` or `-`.
    Unary(UnOp, Box<CExpr>),
    /// A binary operator.
    Binary(BinOp, Box<CExpr>, Box<CExpr>),
    /// Membership in a list.
    In(Box<CExpr>, Vec<CExpr>),
    /// Membership in an inclusive range.
    InRange(Box<CExpr>, Box<CExpr>, Box<CExpr>),
    /// `if c then a else b`.
    If(Box<CExpr>, Box<CExpr>, Box<CExpr>),
    /// `min(a, b)`.
    Min(Box<CExpr>, Box<CExpr>),
    /// `max(a, b)`.
    Max(Box<CExpr>, Box<CExpr>),
}

/// Unary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UnOp {
    /// Logical not.
    Not,
    /// Negation.
    Neg,
}

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinOp {
    /// `||`
    Or,
    /// `&&`
    And,
    /// `==`
    Eq,
    /// `!=`
    Ne,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `|`
    BitOr,
    /// `^`
    BitXor,
    /// `&`
    BitAnd,
    /// `<<`
    Shl,
    /// `>>`
    Shr,
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `%`
    Rem,
}

impl BinOp {
    /// The operator for its spelling.
    pub fn from_symbol(op: &str) -> Option<BinOp> {
        Some(match op {
            "||" => BinOp::Or,
            "&&" => BinOp::And,
            "==" => BinOp::Eq,
            "!=" => BinOp::Ne,
            "<" => BinOp::Lt,
            "<=" => BinOp::Le,
            ">" => BinOp::Gt,
            ">=" => BinOp::Ge,
            "|" => BinOp::BitOr,
            "^" => BinOp::BitXor,
            "&" => BinOp::BitAnd,
            "<<" => BinOp::Shl,
            ">>" => BinOp::Shr,
            "+" => BinOp::Add,
            "-" => BinOp::Sub,
            "*" => BinOp::Mul,
            "/" => BinOp::Div,
            "%" => BinOp::Rem,
            _ => return None,
        })
    }

    /// Whether the operator takes and gives conditions (`&&`, `||`).
    pub fn is_logical(self) -> bool {
        matches!(self, BinOp::Or | BinOp::And)
    }

    /// Whether the operator compares numbers into a condition.
    pub fn is_comparison(self) -> bool {
        matches!(
            self,
            BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge
        )
    }
}

/// Why an expression has no value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EvalError {
    /// Division or remainder by zero.
    DivisionByZero,
    /// An arithmetic result beyond 64 bits, or a shift by 64 or more.
    Overflow,
    /// A field read where no label is being taken.
    NoField(usize),
    /// A slot the state does not have (a state of another model).
    NoSlot(usize),
}

impl fmt::Display for EvalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EvalError::DivisionByZero => f.write_str("division by zero"),
            EvalError::Overflow => f.write_str("arithmetic overflow"),
            EvalError::NoField(i) => write!(f, "field {i} read outside a label"),
            EvalError::NoSlot(i) => write!(f, "slot {i} outside the state"),
        }
    }
}

impl CExpr {
    /// The value in `state`, with `fields` the values of the label being taken.
    pub fn eval(&self, state: &[i64], fields: &[i64]) -> Result<i64, EvalError> {
        Ok(match self {
            CExpr::Const(v) => *v,
            CExpr::Slot(slot) => *state.get(*slot).ok_or(EvalError::NoSlot(*slot))?,
            CExpr::Field(i) => *fields.get(*i).ok_or(EvalError::NoField(*i))?,
            CExpr::At(slot, locations) => {
                i64::from(locations.contains(state.get(*slot).ok_or(EvalError::NoSlot(*slot))?))
            }
            CExpr::Unary(UnOp::Not, e) => i64::from(e.eval(state, fields)? == 0),
            CExpr::Unary(UnOp::Neg, e) => e.eval(state, fields)?.checked_neg().ok_or(EvalError::Overflow)?,
            CExpr::Binary(op, a, b) => {
                let a = a.eval(state, fields)?;
                // Short-circuit, so that `x != 0 && 10 / x > 1` is safe.
                match (op, a) {
                    (BinOp::And, 0) => return Ok(0),
                    (BinOp::Or, a) if a != 0 => return Ok(1),
                    _ => {}
                }
                binary(*op, a, b.eval(state, fields)?)?
            }
            CExpr::In(e, items) => {
                let v = e.eval(state, fields)?;
                for item in items {
                    if item.eval(state, fields)? == v {
                        return Ok(1);
                    }
                }
                0
            }
            CExpr::InRange(e, lo, hi) => {
                let v = e.eval(state, fields)?;
                i64::from(lo.eval(state, fields)? <= v && v <= hi.eval(state, fields)?)
            }
            CExpr::If(c, a, b) => {
                if c.eval(state, fields)? != 0 {
                    a.eval(state, fields)?
                } else {
                    b.eval(state, fields)?
                }
            }
            CExpr::Min(a, b) => a.eval(state, fields)?.min(b.eval(state, fields)?),
            CExpr::Max(a, b) => a.eval(state, fields)?.max(b.eval(state, fields)?),
        })
    }

    /// The value if the expression reads nothing of the state or of a label.
    pub fn constant(&self) -> Option<i64> {
        if self.reads_state() || self.reads_fields() {
            return None;
        }
        self.eval(&[], &[]).ok()
    }

    /// Whether the expression reads a variable or a location.
    pub fn reads_state(&self) -> bool {
        self.any(&|e| matches!(e, CExpr::Slot(_) | CExpr::At(..)))
    }

    /// Whether the expression reads a field of the label.
    pub fn reads_fields(&self) -> bool {
        self.any(&|e| matches!(e, CExpr::Field(_)))
    }

    /// The slots the expression reads.
    pub fn slots(&self, out: &mut Vec<usize>) {
        self.visit(&mut |e| match e {
            CExpr::Slot(s) | CExpr::At(s, _) => out.push(*s),
            _ => {}
        });
    }

    fn any(&self, pred: &dyn Fn(&CExpr) -> bool) -> bool {
        let mut found = false;
        self.visit(&mut |e| found |= pred(e));
        found
    }

    fn visit(&self, f: &mut dyn FnMut(&CExpr)) {
        f(self);
        match self {
            CExpr::Const(_) | CExpr::Slot(_) | CExpr::Field(_) | CExpr::At(..) => {}
            CExpr::Unary(_, e) => e.visit(f),
            CExpr::Binary(_, a, b) | CExpr::Min(a, b) | CExpr::Max(a, b) => {
                a.visit(f);
                b.visit(f);
            }
            CExpr::In(e, items) => {
                e.visit(f);
                items.iter().for_each(|i| i.visit(f));
            }
            CExpr::InRange(a, b, c) | CExpr::If(a, b, c) => {
                a.visit(f);
                b.visit(f);
                c.visit(f);
            }
        }
    }
}

fn binary(op: BinOp, a: i64, b: i64) -> Result<i64, EvalError> {
    let overflow = EvalError::Overflow;
    Ok(match op {
        BinOp::Or => i64::from(a != 0 || b != 0),
        BinOp::And => i64::from(a != 0 && b != 0),
        BinOp::Eq => i64::from(a == b),
        BinOp::Ne => i64::from(a != b),
        BinOp::Lt => i64::from(a < b),
        BinOp::Le => i64::from(a <= b),
        BinOp::Gt => i64::from(a > b),
        BinOp::Ge => i64::from(a >= b),
        BinOp::BitOr => a | b,
        BinOp::BitXor => a ^ b,
        BinOp::BitAnd => a & b,
        BinOp::Shl => {
            let shift = u32::try_from(b).ok().filter(|s| *s < 64).ok_or(overflow)?;
            a.checked_shl(shift).ok_or(EvalError::Overflow)?
        }
        BinOp::Shr => {
            let shift = u32::try_from(b).ok().filter(|s| *s < 64).ok_or(overflow)?;
            a >> shift
        }
        BinOp::Add => a.checked_add(b).ok_or(overflow)?,
        BinOp::Sub => a.checked_sub(b).ok_or(overflow)?,
        BinOp::Mul => a.checked_mul(b).ok_or(overflow)?,
        BinOp::Div => {
            if b == 0 {
                return Err(EvalError::DivisionByZero);
            }
            a.checked_div(b).ok_or(overflow)?
        }
        BinOp::Rem => {
            if b == 0 {
                return Err(EvalError::DivisionByZero);
            }
            a.checked_rem(b).ok_or(overflow)?
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(v: i64) -> Box<CExpr> {
        Box::new(CExpr::Const(v))
    }

    #[test]
    fn arithmetic_is_checked_and_logic_short_circuits() {
        let state = [3, 0];
        let div = CExpr::Binary(BinOp::Div, c(10), Box::new(CExpr::Slot(1)));
        assert_eq!(div.eval(&state, &[]), Err(EvalError::DivisionByZero));
        let guarded = CExpr::Binary(
            BinOp::And,
            Box::new(CExpr::Binary(BinOp::Ne, Box::new(CExpr::Slot(1)), c(0))),
            Box::new(div),
        );
        assert_eq!(guarded.eval(&state, &[]), Ok(0));
        assert_eq!(
            CExpr::Binary(BinOp::Shl, c(1), c(64)).eval(&[], &[]),
            Err(EvalError::Overflow)
        );
        assert_eq!(
            CExpr::Binary(BinOp::Mul, c(i64::MAX), c(2)).eval(&[], &[]),
            Err(EvalError::Overflow)
        );
        assert_eq!(CExpr::At(0, vec![1, 3]).eval(&state, &[]), Ok(1));
        assert_eq!(CExpr::Field(2).eval(&state, &[7]), Err(EvalError::NoField(2)));
        let member = CExpr::In(Box::new(CExpr::Field(0)), vec![CExpr::Const(5), CExpr::Slot(0)]);
        assert_eq!(member.eval(&state, &[3]), Ok(1));
        assert!(member.reads_state() && member.reads_fields());
        assert_eq!(CExpr::Min(c(4), c(2)).constant(), Some(2));
    }
}
