//! Recursive descent over the tokens: a [`File`] plus diagnostics. Never fails as a whole: an item
//! that cannot be read is reported and skipped up to the next line, and reading goes on.

use canopener_eds::diag::Span;

use crate::diagnostics::{MbtCode, MbtDiagnostic, diag};
use crate::syntax::ast::*;
use crate::syntax::lexer::{Tok, Token, lex};

/// The functions of the expression language.
pub const FUNCTIONS: &[&str] = &["od", "exists", "pdo_bytes", "min", "max", "accepted"];

/// Deeper nesting than this is refused, so that hostile input cannot overflow the stack.
const MAX_DEPTH: usize = 64;

/// Reads a model file.
pub fn parse(text: &str) -> (File, Vec<MbtDiagnostic>) {
    let (tokens, diagnostics) = lex(text);
    let mut parser = Parser {
        tokens,
        pos: 0,
        depth: 0,
        diagnostics,
    };
    let file = parser.file();
    (file, parser.diagnostics)
}

/// A syntax error already reported; the caller skips ahead.
struct Reported;

type PResult<T> = Result<T, Reported>;

struct Parser {
    tokens: Vec<Token>,
    pos: usize,
    depth: usize,
    diagnostics: Vec<MbtDiagnostic>,
}

const ITEM_KEYWORDS: &[&str] = &[
    "model",
    "title",
    "cite",
    "use",
    "param",
    "const",
    "let",
    "quiescence",
    "reset",
    "input",
    "output",
    "clock",
    "event",
    "process",
    "purpose",
];

impl Parser {
    fn peek(&self) -> &Token {
        self.token(0)
    }

    fn peek_at(&self, ahead: usize) -> &Tok {
        &self.token(ahead).tok
    }

    /// The token `ahead` past the current one, or the last (the end of the file) beyond it.
    #[allow(
        clippy::indexing_slicing,
        reason = "lex ends every token list with Eof, so it is never empty and its last index is len - 1"
    )]
    fn token(&self, ahead: usize) -> &Token {
        &self.tokens[(self.pos + ahead).min(self.tokens.len() - 1)]
    }

    fn span(&self) -> Span {
        self.peek().span
    }

    fn advance(&mut self) -> Token {
        let token = self.peek().clone();
        if !matches!(token.tok, Tok::Eof) {
            self.pos += 1;
        }
        token
    }

    fn at_punct(&self, p: &str) -> bool {
        matches!(&self.peek().tok, Tok::Punct(q) if *q == p)
    }

    fn at_word(&self, w: &str) -> bool {
        matches!(&self.peek().tok, Tok::Ident(s) if s == w)
    }

    fn eat_punct(&mut self, p: &str) -> bool {
        let at = self.at_punct(p);
        if at {
            self.advance();
        }
        at
    }

    fn eat_word(&mut self, w: &str) -> bool {
        let at = self.at_word(w);
        if at {
            self.advance();
        }
        at
    }

    fn error<T>(&mut self, span: Span, message: impl Into<String>) -> PResult<T> {
        self.diagnostics.push(diag(MbtCode::Syntax, span, message));
        Err(Reported)
    }

    fn describe(tok: &Tok) -> String {
        match tok {
            Tok::Ident(s) => format!("`{s}`"),
            Tok::NodeId => "`$NODEID`".into(),
            Tok::Int { value, .. } => format!("the number {value}"),
            Tok::Str(_) => "a string".into(),
            Tok::Punct(p) => format!("`{p}`"),
            Tok::Eof => "the end of the file".into(),
        }
    }

    fn expect_punct(&mut self, p: &str) -> PResult<()> {
        if self.eat_punct(p) {
            return Ok(());
        }
        let found = Self::describe(&self.peek().tok);
        self.error(self.span(), format!("expected `{p}`, found {found}"))
    }

    fn expect_word(&mut self, w: &str) -> PResult<()> {
        if self.eat_word(w) {
            return Ok(());
        }
        let found = Self::describe(&self.peek().tok);
        self.error(self.span(), format!("expected `{w}`, found {found}"))
    }

    fn name(&mut self, what: &str) -> PResult<Name> {
        let token = self.peek().clone();
        match token.tok {
            Tok::Ident(text) => {
                self.advance();
                Ok(Name {
                    text,
                    span: token.span,
                })
            }
            other => {
                let found = Self::describe(&other);
                self.error(token.span, format!("expected {what}, found {found}"))
            }
        }
    }

    fn string(&mut self, what: &str) -> PResult<String> {
        let token = self.peek().clone();
        match token.tok {
            Tok::Str(text) => {
                self.advance();
                Ok(text)
            }
            other => {
                let found = Self::describe(&other);
                self.error(token.span, format!("expected {what} in quotes, found {found}"))
            }
        }
    }

    /// Skips to the first token of a later line than the error (or a closing brace on the same one).
    fn recover(&mut self, line: u32) {
        while !matches!(self.peek().tok, Tok::Eof) && self.peek().span.line <= line && !self.at_punct("}") {
            self.advance();
        }
    }

    fn file(&mut self) -> File {
        let mut file = File::default();
        while !matches!(self.peek().tok, Tok::Eof) {
            let line = self.span().line;
            if self.item(&mut file).is_err() {
                self.recover(line);
                if self.at_punct("}") {
                    self.advance();
                }
            }
        }
        if file.name.is_none() {
            self.diagnostics.push(diag(
                MbtCode::NoModelName,
                Span::new(1, 1, 0),
                "the file has no `model NAME` line; start it with e.g. `model nmt`",
            ));
        }
        file
    }

    fn item(&mut self, file: &mut File) -> PResult<()> {
        let span = self.span();
        let Tok::Ident(word) = self.peek().tok.clone() else {
            let found = Self::describe(&self.peek().tok);
            return self.error(
                span,
                format!("expected one of {}, found {found}", ITEM_KEYWORDS.join(", ")),
            );
        };
        match word.as_str() {
            "model" => {
                self.advance();
                let name = self.name("the model's name")?;
                if file.name.is_some() {
                    self.diagnostics
                        .push(diag(MbtCode::Duplicate, name.span, "a second `model` line"));
                } else {
                    file.name = Some(name);
                }
            }
            "title" => {
                self.advance();
                file.title = Some(self.string("the title")?);
            }
            "cite" => {
                self.advance();
                file.cites.push(self.string("the clause cited")?);
            }
            "use" => {
                self.advance();
                let token = self.peek().clone();
                let name = match token.tok {
                    Tok::Str(text) => {
                        self.advance();
                        Name {
                            text,
                            span: token.span,
                        }
                    }
                    _ => self.name("a model name or a file in quotes")?,
                };
                file.uses.push(name);
            }
            "param" | "const" | "let" => {
                self.advance();
                let kind = match word.as_str() {
                    "param" => DefKind::Param,
                    "const" => DefKind::Const,
                    _ => DefKind::Let,
                };
                let name = self.name("a name")?;
                self.expect_punct("=")?;
                let value = self.expr()?;
                let fallback = if kind == DefKind::Param && self.eat_word("else") {
                    Some(self.expr()?)
                } else {
                    None
                };
                file.definitions.push(Definition {
                    kind,
                    name,
                    value,
                    fallback,
                });
            }
            "quiescence" => {
                self.advance();
                file.quiescence = Some(self.expr()?);
            }
            "reset" => {
                self.advance();
                file.resets.push(self.action()?);
            }
            "input" | "output" => {
                self.advance();
                let direction = if word == "input" {
                    Direction::Input
                } else {
                    Direction::Output
                };
                file.gates.push(self.gate(direction)?);
            }
            "clock" | "event" => {
                self.advance();
                loop {
                    if word == "clock" {
                        file.clocks.push(self.name("a clock name")?);
                    } else {
                        file.events.push(self.name("an event name")?);
                    }
                    if !self.eat_punct(",") {
                        break;
                    }
                }
            }
            "process" => {
                self.advance();
                file.processes.push(self.process()?);
            }
            "purpose" => {
                self.advance();
                file.purposes.push(self.purpose()?);
            }
            other => {
                return self.error(
                    span,
                    format!(
                        "`{other}` does not start an item; expected one of {}",
                        ITEM_KEYWORDS.join(", ")
                    ),
                );
            }
        }
        Ok(())
    }

    fn gate(&mut self, direction: Direction) -> PResult<GateDecl> {
        let name = self.name("the gate's name")?;
        self.expect_punct("=")?;
        let cob_id = self.expr()?;
        let remote = self.eat_word("rtr");
        self.expect_punct("(")?;
        let mut fields = Vec::new();
        while !self.at_punct(")") {
            let field = self.name("a field name")?;
            self.expect_punct(":")?;
            let span = self.span();
            let ty = if self.eat_word("u8") {
                FieldType::Unsigned(1)
            } else if self.eat_word("u16") {
                FieldType::Unsigned(2)
            } else if self.eat_word("u32") {
                FieldType::Unsigned(4)
            } else if self.eat_word("bytes") {
                self.expect_punct("(")?;
                let n = self.expr()?;
                self.expect_punct(")")?;
                FieldType::Bytes(n)
            } else {
                return self.error(span, "expected a field type: u8, u16, u32 or bytes(N)");
            };
            fields.push(FieldDecl { name: field, ty });
            if !self.eat_punct(",") {
                break;
            }
        }
        self.expect_punct(")")?;
        Ok(GateDecl {
            direction,
            name,
            cob_id,
            remote,
            fields,
        })
    }

    fn process(&mut self) -> PResult<ProcessDecl> {
        let name = self.name("the process's name")?;
        self.expect_punct("{")?;
        let mut process = ProcessDecl {
            name,
            vars: Vec::new(),
            locations: Vec::new(),
            transitions: Vec::new(),
        };
        loop {
            if self.eat_punct("}") {
                return Ok(process);
            }
            if matches!(self.peek().tok, Tok::Eof) {
                let span = self.span();
                return self.error(
                    span,
                    format!("the process `{}` is not closed with `}}`", process.name.text),
                );
            }
            let line = self.span().line;
            if self.process_item(&mut process).is_err() {
                self.recover(line);
            }
        }
    }

    fn process_item(&mut self, process: &mut ProcessDecl) -> PResult<()> {
        if self.eat_word("var") {
            let name = self.name("a variable name")?;
            self.expect_punct(":")?;
            let ty = self.type_decl()?;
            self.expect_punct("=")?;
            let init = self.expr()?;
            process.vars.push(VarDecl { name, ty, init });
        } else if self.eat_word("location") {
            loop {
                let name = self.name("a location name")?;
                let quiescence = if self.eat_word("quiescence") {
                    Some(self.expr()?)
                } else {
                    None
                };
                process.locations.push(LocationDecl { name, quiescence });
                if !self.eat_punct(",") {
                    break;
                }
            }
        } else {
            process.transitions.push(self.transition()?);
        }
        Ok(())
    }

    fn type_decl(&mut self) -> PResult<TypeDecl> {
        let span = self.span();
        let bound = |hi: i64| {
            TypeDecl::Range(
                Expr {
                    kind: ExprKind::Int(0),
                    span,
                },
                Expr {
                    kind: ExprKind::Int(hi),
                    span,
                },
            )
        };
        if self.eat_word("bool") {
            Ok(TypeDecl::Bool)
        } else if self.eat_word("u8") {
            Ok(bound(0xFF))
        } else if self.eat_word("u16") {
            Ok(bound(0xFFFF))
        } else if self.eat_word("u32") {
            Ok(bound(0xFFFF_FFFF))
        } else {
            let lo = self.additive()?;
            self.expect_punct("..")?;
            let hi = self.additive()?;
            Ok(TypeDecl::Range(lo, hi))
        }
    }

    fn transition(&mut self) -> PResult<TransitionDecl> {
        let span = self.span();
        let mut from = Vec::new();
        if !self.eat_word("any") {
            loop {
                from.push(self.name("a location (or `any`) to start a transition")?);
                if !self.eat_punct(",") {
                    break;
                }
            }
        }
        self.expect_punct("->")?;
        let to = if self.eat_word("same") {
            None
        } else {
            Some(self.name("the target location (or `same` to stay)")?)
        };
        self.expect_punct(":")?;
        let kind_span = self.span();
        let mut event = None;
        let (kind, action) = if self.eat_word("in") {
            (ActionKind::Input, Some(self.action()?))
        } else if self.eat_word("out") {
            (ActionKind::Output, Some(self.action()?))
        } else if self.eat_word("maybe") {
            self.expect_word("out")?;
            (ActionKind::MaybeOutput, Some(self.action()?))
        } else if self.eat_word("internal") {
            (ActionKind::Internal, None)
        } else if self.eat_word("signal") {
            event = Some(self.name("the event to signal")?);
            (ActionKind::Signal, None)
        } else if self.eat_word("on") {
            event = Some(self.name("the event to follow")?);
            (ActionKind::On, None)
        } else {
            return self.error(
                kind_span,
                "expected `in GATE(...)`, `out GATE(...)`, `maybe out GATE(...)`, `internal`, `signal EVENT` or `on EVENT`",
            );
        };
        let mut t = TransitionDecl {
            from,
            to,
            kind,
            action,
            event,
            passive: false,
            otherwise: false,
            guards: Vec::new(),
            updates: Vec::new(),
            resets: Vec::new(),
            window: None,
            tags: Vec::new(),
            span,
        };
        loop {
            if self.eat_word("when") {
                t.guards.push(self.expr()?);
            } else if self.eat_word("do") {
                loop {
                    let var = self.name("a variable to assign")?;
                    self.expect_punct(":=")?;
                    t.updates.push((var, self.expr()?));
                    if !self.eat_punct(",") {
                        break;
                    }
                }
            } else if self.eat_word("reset") {
                loop {
                    t.resets.push(self.name("a clock")?);
                    if !self.eat_punct(",") {
                        break;
                    }
                }
            } else if self.eat_word("within") {
                let lo = self.additive()?;
                self.expect_punct("..")?;
                let hi = self.additive()?;
                self.expect_word("of")?;
                let clock = self.name("a clock")?;
                if t.window.is_some() {
                    self.diagnostics
                        .push(diag(MbtCode::Duplicate, clock.span, "a second `within` window"));
                }
                t.window = Some(Window { lo, hi, clock });
            } else if self.eat_word("tag") {
                t.tags.push(self.string("a requirement tag")?);
            } else if self.at_word("passive") || self.at_word("otherwise") {
                let word = self.advance();
                if t.kind != ActionKind::Input {
                    return self.error(
                        word.span,
                        "only an input (`in GATE(...)`) can be `passive` or `otherwise`",
                    );
                }
                t.passive = true;
                t.otherwise |= matches!(&word.tok, Tok::Ident(w) if w == "otherwise");
            } else {
                return Ok(t);
            }
        }
    }

    fn action(&mut self) -> PResult<Action> {
        let span = self.span();
        let gate = self.name("a gate")?;
        let mut args = Vec::new();
        if self.eat_punct("(") {
            while !self.at_punct(")") {
                let field = match (self.peek().tok.clone(), self.peek_at(1)) {
                    (Tok::Ident(text), Tok::Punct("=")) => {
                        let span = self.advance().span;
                        self.advance();
                        Some(Name { text, span })
                    }
                    _ => None,
                };
                let pattern = self.pattern()?;
                args.push(Arg { field, pattern });
                if !self.eat_punct(",") {
                    break;
                }
            }
            self.expect_punct(")")?;
        }
        Ok(Action { gate, args, span })
    }

    fn pattern(&mut self) -> PResult<Pattern> {
        let span = self.span();
        if self.eat_word("_") {
            return Ok(Pattern::Any(span));
        }
        if self.eat_punct("{") {
            let items = self.expr_list("}")?;
            return Ok(Pattern::Set(items, span));
        }
        let value = self.expr()?;
        if self.eat_punct("..") {
            let hi = self.additive()?;
            return Ok(Pattern::Range(value, hi));
        }
        Ok(Pattern::Value(value))
    }

    fn expr_list(&mut self, close: &str) -> PResult<Vec<Expr>> {
        let mut items = Vec::new();
        while !self.at_punct(close) {
            items.push(self.expr()?);
            if !self.eat_punct(",") {
                break;
            }
        }
        self.expect_punct(close)?;
        Ok(items)
    }

    fn purpose(&mut self) -> PResult<PurposeDecl> {
        let name = self.name("the purpose's name")?;
        let title = if matches!(self.peek().tok, Tok::Str(_)) {
            Some(self.string("the title")?)
        } else {
            None
        };
        self.expect_punct("{")?;
        let mut purpose = PurposeDecl {
            name,
            title,
            states: Vec::new(),
            transitions: Vec::new(),
        };
        loop {
            if self.eat_punct("}") {
                return Ok(purpose);
            }
            if matches!(self.peek().tok, Tok::Eof) {
                let span = self.span();
                return self.error(
                    span,
                    format!("the purpose `{}` is not closed with `}}`", purpose.name.text),
                );
            }
            let line = self.span().line;
            if self.purpose_item(&mut purpose).is_err() {
                self.recover(line);
            }
        }
    }

    fn purpose_item(&mut self, purpose: &mut PurposeDecl) -> PResult<()> {
        if self.eat_word("state") {
            loop {
                let name = self.name("a state name")?;
                let marker = if self.eat_word("accept") {
                    Marker::Accept
                } else if self.eat_word("refuse") {
                    Marker::Refuse
                } else {
                    Marker::None
                };
                purpose.states.push((name, marker));
                if !self.eat_punct(",") {
                    break;
                }
            }
            return Ok(());
        }
        let span = self.span();
        let from = self.name("a state or `state`")?;
        self.expect_punct("->")?;
        let to = self.name("the target state")?;
        self.expect_punct(":")?;
        let pattern = if self.eat_punct("*") {
            LabelPatternDecl::Otherwise
        } else if self.eat_word("quiescence") {
            LabelPatternDecl::Quiescence
        } else {
            let direction = if self.eat_word("in") {
                Some(Direction::Input)
            } else if self.eat_word("out") {
                Some(Direction::Output)
            } else {
                None
            };
            let action = self.action()?;
            let guard = if self.eat_word("when") {
                Some(self.expr()?)
            } else {
                None
            };
            LabelPatternDecl::Gate {
                direction,
                action,
                guard,
            }
        };
        purpose.transitions.push(PurposeTransitionDecl {
            from,
            to,
            pattern,
            span,
        });
        Ok(())
    }

    // Expressions, lowest precedence first.

    /// Reads an expression.
    fn expr(&mut self) -> PResult<Expr> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            self.depth -= 1;
            let span = self.span();
            return self.error(span, format!("expressions nest deeper than {MAX_DEPTH} levels"));
        }
        let result = self.binary_level(0);
        self.depth -= 1;
        result
    }

    fn additive(&mut self) -> PResult<Expr> {
        self.binary_level(7)
    }

    fn binary_level(&mut self, level: usize) -> PResult<Expr> {
        const LEVELS: &[&[&str]] = &[
            &["||"],
            &["&&"],
            &["==", "!=", "<", "<=", ">", ">="],
            &["|"],
            &["^"],
            &["&"],
            &["<<", ">>"],
            &["+", "-"],
            &["*", "/", "%"],
        ];
        let Some(operators) = LEVELS.get(level) else {
            return self.unary();
        };
        let mut left = self.binary_level(level + 1)?;
        loop {
            if level == 2 && self.at_word("in") {
                self.advance();
                left = self.in_expr(left)?;
                continue;
            }
            let Some(op) = operators.iter().find(|op| self.at_punct(op)) else {
                return Ok(left);
            };
            self.advance();
            let right = self.binary_level(level + 1)?;
            let span = left.span;
            left = Expr {
                kind: ExprKind::Binary(op, Box::new(left), Box::new(right)),
                span,
            };
        }
    }

    fn in_expr(&mut self, left: Expr) -> PResult<Expr> {
        let span = left.span;
        if self.eat_punct("{") {
            let items = self.expr_list("}")?;
            return Ok(Expr {
                kind: ExprKind::In(Box::new(left), items),
                span,
            });
        }
        let lo = self.additive()?;
        self.expect_punct("..")?;
        let hi = self.additive()?;
        Ok(Expr {
            kind: ExprKind::InRange(Box::new(left), Box::new(lo), Box::new(hi)),
            span,
        })
    }

    fn unary(&mut self) -> PResult<Expr> {
        let span = self.span();
        for op in ["!", "-"] {
            if self.eat_punct(op) {
                self.depth += 1;
                if self.depth > MAX_DEPTH {
                    self.depth -= 1;
                    return self.error(span, format!("expressions nest deeper than {MAX_DEPTH} levels"));
                }
                let inner = self.unary();
                self.depth -= 1;
                return Ok(Expr {
                    kind: ExprKind::Unary(op, Box::new(inner?)),
                    span,
                });
            }
        }
        self.primary()
    }

    fn primary(&mut self) -> PResult<Expr> {
        let token = self.advance();
        let span = token.span;
        let kind = match token.tok {
            Tok::Int { value, .. } => ExprKind::Int(value),
            Tok::NodeId => ExprKind::NodeId,
            Tok::Punct("(") => {
                let inner = self.expr()?;
                self.expect_punct(")")?;
                return Ok(inner);
            }
            Tok::Ident(word) => match word.as_str() {
                "true" => ExprKind::Bool(true),
                "false" => ExprKind::Bool(false),
                "if" => {
                    let cond = self.expr()?;
                    self.expect_word("then")?;
                    let then = self.expr()?;
                    self.expect_word("else")?;
                    let otherwise = self.expr()?;
                    ExprKind::If(Box::new(cond), Box::new(then), Box::new(otherwise))
                }
                // Only the language's functions take arguments, so that a name can end the COB-ID
                // of a gate before its field list: `input PEER = 0x700 + WATCH (state: u8)`.
                _ if self.at_punct("(") && FUNCTIONS.contains(&word.as_str()) => {
                    self.advance();
                    ExprKind::Call(word, self.expr_list(")")?)
                }
                _ if self.at_punct(".") => {
                    self.advance();
                    let member = self.name("a variable of the process")?;
                    ExprKind::Member(word, member.text)
                }
                _ if self.at_punct("@") => {
                    self.advance();
                    let locations = if self.eat_punct("{") {
                        let mut names = Vec::new();
                        while !self.at_punct("}") {
                            names.push(self.name("a location")?);
                            if !self.eat_punct(",") {
                                break;
                            }
                        }
                        self.expect_punct("}")?;
                        names
                    } else {
                        vec![self.name("a location")?]
                    };
                    ExprKind::At(word, locations)
                }
                _ => ExprKind::Name(word),
            },
            other => {
                let found = Self::describe(&other);
                return self.error(span, format!("expected a value, a name or `(`, found {found}"));
            }
        };
        Ok(Expr { kind, span })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_ok(text: &str) -> File {
        let (file, diagnostics) = parse(text);
        assert!(diagnostics.is_empty(), "{diagnostics:#?}");
        file
    }

    #[test]
    fn a_small_model_reads_completely() {
        let file = parse_ok(
            r#"
model nmt
title "NMT"
cite "CiA 301 §7.3.2"
param BOOT = od(0x1017, 0) else 1000ms
input NMT = 0x000 (cs: u8, node: u8)
output EC = 0x700 + $NODEID (state: u8)
input GUARD = 0x700 + $NODEID rtr (state: u8)
clock t
reset NMT(0x81, $NODEID)
process nmt {
  var n: 0..3 = 0
  location Init, PreOp quiescence 2s
  Init -> PreOp: out EC(0) within 0..BOOT of t reset t tag "301:T2"
  PreOp -> same: in NMT(cs = {0x01, 0x02}, node = 0..127) when node in {0, $NODEID} && !(n == 3) do n := n + 1
}
purpose p "reach" {
  state a, b accept
  a -> b: out EC(state = 0x05) when state != 0
  a -> a: *
}
"#,
        );
        assert_eq!(file.name.unwrap().text, "nmt");
        assert_eq!(file.gates.len(), 3);
        assert!(file.gates[2].remote);
        assert_eq!(
            file.definitions[0].fallback.as_ref().unwrap().kind,
            ExprKind::Int(1_000_000)
        );
        let p = &file.processes[0];
        assert_eq!(p.locations.len(), 2);
        assert!(p.locations[1].quiescence.is_some());
        assert_eq!(p.transitions.len(), 2);
        let t = &p.transitions[0];
        assert_eq!(t.kind, ActionKind::Output);
        assert_eq!(t.window.as_ref().unwrap().clock.text, "t");
        assert_eq!(t.tags, ["301:T2"]);
        let t = &p.transitions[1];
        assert_eq!(
            t.action.as_ref().unwrap().args[0].field.as_ref().unwrap().text,
            "cs"
        );
        assert!(matches!(
            t.action.as_ref().unwrap().args[1].pattern,
            Pattern::Range(..)
        ));
        assert_eq!(t.updates.len(), 1);
        assert_eq!(file.purposes[0].states[1].1, Marker::Accept);
        assert_eq!(
            file.purposes[0].transitions[1].pattern,
            LabelPatternDecl::Otherwise
        );
    }

    #[test]
    fn precedence_binds_as_in_c() {
        let file = parse_ok("model m\nconst X = 1 + 2 * 3 == 7 && 1 << 2 | 1 == 5");
        let ExprKind::Binary(op, left, right) = &file.definitions[0].value.kind else {
            panic!()
        };
        assert_eq!(*op, "&&");
        assert!(matches!(left.kind, ExprKind::Binary("==", ..)));
        assert!(matches!(right.kind, ExprKind::Binary("==", ..)));
    }

    #[test]
    fn errors_name_the_place_and_reading_goes_on() {
        let (file, diagnostics) = parse(
            "model m\nprocess p {\n  location A\n  A -> : in X\n  A -> A: internal\n}\nbogus 3\ninput G = 1 (a: u8)\n",
        );
        let places: Vec<(u32, u32, &str)> = diagnostics
            .iter()
            .map(|d| (d.span.line, d.span.column, d.code.as_str()))
            .collect();
        assert_eq!(places, [(4, 8, "M001"), (7, 1, "M001")], "{diagnostics:#?}");
        assert!(diagnostics[0].message.contains("expected the target location"));
        assert_eq!(file.processes[0].transitions.len(), 1);
        assert_eq!(file.gates.len(), 1);
    }

    #[test]
    fn missing_model_line_and_deep_nesting_are_reported() {
        let (_, d) = parse("const X = 1");
        assert_eq!(d[0].code, MbtCode::NoModelName);
        let deep = format!("model m\nconst X = {}1{}", "(".repeat(500), ")".repeat(500));
        let (_, d) = parse(&deep);
        assert!(d.iter().any(|d| d.message.contains("nest deeper")), "{d:?}");
        let (_, d) = parse(&format!("model m\nconst X = {}1", "!".repeat(5000)));
        assert!(d.iter().any(|d| d.message.contains("nest deeper")), "{d:?}");
    }
}
