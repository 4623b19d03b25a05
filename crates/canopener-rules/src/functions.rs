//! The function library rules call beyond CEL's standard library and the strings, math and lists
//! extensions: uniqueness, counts, bit tests, ranges, EDS numbers and lookups in the file.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use canopener_eds::value::parse_integer;
use cel::common::types::{CelList, CelMap, CelMapKey, CelNull, CelString, STRING_TYPE};
use cel::common::value::CowVal;
use cel::objects::Key;
use cel::{Env, ExecutionError, FunctionContext, Value};

use crate::items::objects_of;

/// The functions this crate adds, with their signatures, for documentation and error messages.
pub const FUNCTIONS: &[(&str, &str)] = &[
    ("unique", "unique(list) -> bool: no value occurs twice"),
    (
        "duplicates",
        "duplicates(list) -> list: every value that occurs more than once, once each",
    ),
    ("count", "count(list, value) -> int: how often value occurs"),
    (
        "bit",
        "bit(int, n) -> bool: whether bit n (0 = least significant) is set",
    ),
    (
        "bits",
        "bits(int, lo, count) -> int: count bits from bit lo, shifted down",
    ),
    (
        "in_range",
        "in_range(x, lo, hi) -> bool: lo <= x <= hi for ints, uints and doubles",
    ),
    (
        "number",
        "number(text) -> int or null: an EDS integer (decimal, 0x hex, 0 octal, $NODEID+n)",
    ),
    (
        "hex",
        "hex(int) / hex(int, digits) -> string: 0x and upper-case hex digits, zero-padded",
    ),
    (
        "key",
        "key(item, name) -> string or null: the value of a key, name compared case-insensitively",
    ),
    (
        "replace",
        "replace(text, from, to) -> string: every occurrence of from replaced by to",
    ),
    (
        "has_object",
        "has_object(index) -> bool: the object is in the file",
    ),
    (
        "has_sub",
        "has_sub(index, sub) -> bool: the sub-object is in the file",
    ),
    ("object", "object(index) -> item or null"),
    ("sub", "sub(index, sub) -> item or null"),
    (
        "subs",
        "subs(index) -> list of items: the sub-objects of an object, by sub-index",
    ),
];

/// The hidden variable holding the `eds` value for the lookup functions: users cannot write a name
/// starting with `@`, so a comprehension variable called `eds` cannot hide it.
pub(crate) const EDS_VAR: &str = "@eds";

/// What the file-dependent functions look up.
#[derive(Debug, Default)]
pub(crate) struct FileIndex {
    /// The position in `eds.objects` of every object (`None`) and sub-object.
    pub(crate) positions: HashMap<(u16, Option<u8>), usize>,
    /// The sub-indices of each object, ascending.
    pub(crate) subs: HashMap<u16, Vec<u8>>,
    /// The node-ID `$NODEID` resolves with.
    pub(crate) node_id: u8,
}

/// A function that may return a value borrowed from the context (an item of `eds.objects`), which
/// the argument-extracting closures of `cel` cannot.
type Raw = Box<
    dyn for<'c, 'k> Fn(&mut FunctionContext<'c, 'k>) -> Result<CowVal<'c, 'k>, ExecutionError> + Send + Sync,
>;

/// The item at `position` of `eds.objects`, borrowed.
fn item_at<'c, 'k>(f: &FunctionContext<'c, 'k>, position: usize) -> Result<CowVal<'c, 'k>, ExecutionError> {
    let ptx: &'c cel::Context<'c, 'k> = f.ptx;
    let missing = || fail(f.name, "the file's objects are not available here");
    match ptx.get_variable(EDS_VAR).ok_or_else(missing)? {
        CowVal::Borrowed(eds) => objects_of(eds)
            .and_then(|objects| objects.get(position))
            .map(|item| CowVal::Borrowed(item.as_ref()))
            .ok_or_else(missing),
        CowVal::Owned(_) => Err(missing()),
    }
}

/// The call's arguments as plain values (ints and strings here, so converting is cheap).
fn raw_ints<const N: usize>(f: &FunctionContext<'_, '_>) -> Result<[Value; N], ExecutionError> {
    args::<N>(f, f.name)
}

/// The environment every rule is compiled and run in: CEL's standard library, the strings, math
/// and lists extensions, and the global `replace(text, from, to)`.
pub(crate) fn environment() -> Env {
    let mut env = Env::stdlib();
    // The extensions and the overload below are registered on a fresh environment with names no one
    // else uses; a failure would be a programming error caught by every test, so it is ignored here
    // rather than turned into a panic.
    let _ = env.add_extension(cel::extensions::strings);
    let _ = env.add_extension(cel::extensions::math);
    let _ = env.add_extension(cel::extensions::lists);
    // The strings extension declares the member `text.replace(from, to)`, so a global function of that
    // name can only be added as an overload (a context function would conflict with it).
    let _ = env.add_overload(
        "replace",
        "replace_string_string_string",
        vec![STRING_TYPE, STRING_TYPE, STRING_TYPE],
        replace_global,
    );
    env
}

fn replace_global<'b, 'v>(args: Vec<CowVal<'b, 'v>>) -> Result<CowVal<'b, 'v>, ExecutionError> {
    let text = |i: usize| {
        args.get(i)
            .and_then(|a| a.downcast_ref::<CelString<'_>>())
            .map(|s| s.inner().to_owned())
            .ok_or_else(|| ExecutionError::function_error("replace", "expects (string, string, string)"))
    };
    let (text, from, to) = (text(0)?, text(1)?, text(2)?);
    if from.is_empty() {
        return Err(ExecutionError::function_error(
            "replace",
            "cannot replace an empty string",
        ));
    }
    Ok(CowVal::owned(CelString::from(text.replace(&from, &to))))
}

/// Adds the library to a root context; `file` answers the lookups.
pub(crate) fn install(ctx: &mut cel::Context<'_, '_>, file: &Arc<FileIndex>) {
    // Names are fixed and unused by the environment (see `environment`): adding cannot fail.
    let _ = ctx.add_function("unique", |f: &FunctionContext<'_, '_>| {
        let [list] = args::<1>(f, "unique")?;
        let list = as_list(&list, "unique")?;
        Ok::<_, ExecutionError>(Value::Bool(duplicates(&list).is_empty()))
    });
    let _ = ctx.add_function("duplicates", |f: &FunctionContext<'_, '_>| {
        let [list] = args::<1>(f, "duplicates")?;
        let list = as_list(&list, "duplicates")?;
        Ok::<_, ExecutionError>(Value::List(Arc::new(duplicates(&list))))
    });
    let _ = ctx.add_function("count", |f: &FunctionContext<'_, '_>| {
        let [list, value] = args::<2>(f, "count")?;
        let list = as_list(&list, "count")?;
        let n = list.iter().filter(|v| **v == value).count();
        Ok::<_, ExecutionError>(Value::Int(i64::try_from(n).unwrap_or(i64::MAX)))
    });
    let _ = ctx.add_function("bit", |f: &FunctionContext<'_, '_>| {
        let [x, n] = args::<2>(f, "bit")?;
        let (x, n) = (as_bits(&x, "bit")?, as_int(&n, "bit")?);
        let n = u32::try_from(n)
            .ok()
            .filter(|n| *n < 64)
            .ok_or_else(|| fail("bit", format!("bit number {n} is outside 0..=63")))?;
        Ok::<_, ExecutionError>(Value::Bool(x >> n & 1 == 1))
    });
    let _ = ctx.add_function("bits", |f: &FunctionContext<'_, '_>| {
        let [x, lo, count] = args::<3>(f, "bits")?;
        let (x, lo, count) = (
            as_bits(&x, "bits")?,
            as_int(&lo, "bits")?,
            as_int(&count, "bits")?,
        );
        let fits = (0..64).contains(&lo) && (1..=64).contains(&count) && lo + count <= 64;
        if !fits {
            return Err(fail(
                "bits",
                format!("bits({lo}, {count}) does not fit in 64 bits"),
            ));
        }
        // `fits` proved 0 <= lo < 64 and 1 <= count <= 64 - lo.
        let shifted = x >> lo;
        let mask = if count == 64 {
            u64::MAX
        } else {
            (1u64 << count) - 1
        };
        // 64 bits of an int come back as the same pattern: `bits(-1, 0, 64) == -1`.
        Ok(Value::Int((shifted & mask) as i64))
    });
    let _ = ctx.add_function("in_range", |f: &FunctionContext<'_, '_>| {
        let [x, lo, hi] = args::<3>(f, "in_range")?;
        let (x, lo, hi) = (as_number(&x)?, as_number(&lo)?, as_number(&hi)?);
        Ok::<_, ExecutionError>(Value::Bool(lo.le(&x) && x.le(&hi)))
    });
    let _ = ctx.add_function("hex", |f: &FunctionContext<'_, '_>| {
        let all = all_args(f);
        let (x, digits) = match all.as_slice() {
            [x] => (x, None),
            [x, digits] => (x, Some(as_int(digits, "hex")?)),
            _ => return Err(fail("hex", "expects hex(int) or hex(int, digits)")),
        };
        let x = as_int(x, "hex")?;
        let digits = usize::try_from(digits.unwrap_or(1)).unwrap_or(1).min(16);
        Ok(Value::String(Arc::new(if x < 0 {
            format!("-0x{:0digits$X}", x.unsigned_abs())
        } else {
            format!("0x{x:0digits$X}")
        })))
    });
    let index = Arc::clone(file);
    let _ = ctx.add_function("number", move |f: &FunctionContext<'_, '_>| {
        let [text] = args::<1>(f, "number")?;
        Ok::<_, ExecutionError>(match text {
            Value::String(s) => eds_number(&s, index.node_id).map_or(Value::Null, Value::Int),
            Value::Int(i) => Value::Int(i),
            Value::UInt(u) => i64::try_from(u).map_or(Value::Null, Value::Int),
            Value::Null => Value::Null,
            other => {
                return Err(fail(
                    "number",
                    format!("expects a string, got {}", type_name(&other)),
                ));
            }
        })
    });
    let index = Arc::clone(file);
    let _ = ctx.add_function("has_object", move |f: &FunctionContext<'_, '_>| {
        let [i] = args::<1>(f, "has_object")?;
        let i = as_index(&i, "has_object")?;
        Ok::<_, ExecutionError>(Value::Bool(
            i.is_some_and(|i| index.positions.contains_key(&(i, None))),
        ))
    });
    let index = Arc::clone(file);
    let _ = ctx.add_function("has_sub", move |f: &FunctionContext<'_, '_>| {
        let [i, s] = args::<2>(f, "has_sub")?;
        let key = as_index(&i, "has_sub")?.zip(as_sub(&s, "has_sub")?);
        Ok::<_, ExecutionError>(Value::Bool(
            key.is_some_and(|(i, s)| index.positions.contains_key(&(i, Some(s)))),
        ))
    });
    let index = Arc::clone(file);
    let object: Raw = Box::new(move |f| {
        let [i] = raw_ints::<1>(f)?;
        match as_index(&i, "object")?.and_then(|i| index.positions.get(&(i, None))) {
            Some(&position) => item_at(f, position),
            None => Ok(CowVal::owned(CelNull)),
        }
    });
    let _ = ctx.add_function("object", object);
    let index = Arc::clone(file);
    let sub: Raw = Box::new(move |f| {
        let [i, s] = raw_ints::<2>(f)?;
        let key = as_index(&i, "sub")?.zip(as_sub(&s, "sub")?);
        match key.and_then(|(i, s)| index.positions.get(&(i, Some(s)))) {
            Some(&position) => item_at(f, position),
            None => Ok(CowVal::owned(CelNull)),
        }
    });
    let _ = ctx.add_function("sub", sub);
    let index = Arc::clone(file);
    let subs: Raw = Box::new(move |f| {
        let [i] = raw_ints::<1>(f)?;
        let mut items = Vec::new();
        if let Some(i) = as_index(&i, "subs")? {
            for s in index.subs.get(&i).into_iter().flatten() {
                if let Some(&position) = index.positions.get(&(i, Some(*s))) {
                    // A new list owns its elements: each item is copied.
                    items.push(item_at(f, position)?.into_owned());
                }
            }
        }
        Ok(CowVal::owned(CelList::from(items)))
    });
    let _ = ctx.add_function("subs", subs);
    let key: Raw = Box::new(|f| {
        let all: Vec<&CowVal<'_, '_>> = f.this.iter().chain(f.args.iter()).collect();
        let [item, name] = all.as_slice() else {
            return Err(fail("key", format!("expects 2 argument(s), got {}", all.len())));
        };
        let name = name
            .downcast_ref::<CelString<'_>>()
            .ok_or_else(|| fail("key", "expects a key name (string) as its second argument"))?
            .inner()
            .to_owned();
        let keys = item
            .downcast_ref::<CelMap<'_>>()
            .and_then(|m| m.inner().get(&CelMapKey::from("keys")))
            .and_then(|k| k.downcast_ref::<CelMap<'_>>())
            .ok_or_else(|| fail("key", "expects an item (with `keys`) as its first argument"))?;
        let found = keys.inner().iter().find_map(|(k, v)| {
            let k = k.inner().downcast_ref::<CelString<'_>>()?;
            k.inner().eq_ignore_ascii_case(&name).then(|| v.clone())
        });
        Ok(match found {
            Some(v) => CowVal::Owned(v),
            None => CowVal::owned(CelNull),
        })
    });
    let _ = ctx.add_function("key", key);
}

/// Reads an EDS integer (CiA 306 §4.2: decimal, `0x` hex, leading-`0` octal) or a `$NODEID`
/// formula resolved with `node_id`; `None` when the text is no integer or leaves the int64 range.
pub(crate) fn eds_number(text: &str, node_id: u8) -> Option<i64> {
    let text = text.trim();
    let value = if canopener_eds::value::mentions_nodeid(text) {
        let mut total = 0i128;
        let mut nodes = 0;
        for term in text.split('+') {
            let term = term.trim();
            if term.eq_ignore_ascii_case("$NODEID") {
                nodes += 1;
                total = total.checked_add(i128::from(node_id))?;
            } else {
                total = total.checked_add(parse_integer(term, &mut Vec::new())?.value)?;
            }
        }
        (nodes == 1).then_some(total)?
    } else {
        parse_integer(text, &mut Vec::new())?.value
    };
    i64::try_from(value).ok()
}

/// Every value occurring more than once, once each, in order of first occurrence.
fn duplicates(list: &[Value]) -> Vec<Value> {
    let mut out: Vec<Value> = Vec::new();
    let hashable = list.iter().all(|v| {
        matches!(
            v,
            Value::Int(_) | Value::UInt(_) | Value::String(_) | Value::Bool(_)
        )
    });
    if hashable {
        let mut seen: HashSet<Key> = HashSet::new();
        let mut reported: HashSet<Key> = HashSet::new();
        for v in list {
            // Ints and uints with the same value are equal in CEL: key them alike.
            let key = match v {
                Value::UInt(u) => i64::try_from(*u).map_or(Key::Uint(*u), Key::Int),
                Value::Int(i) => Key::Int(*i),
                Value::String(s) => Key::String(Arc::clone(s)),
                Value::Bool(b) => Key::Bool(*b),
                _ => continue,
            };
            if !seen.insert(key.clone()) && reported.insert(key) {
                out.push(v.clone());
            }
        }
    } else {
        for (i, v) in list.iter().enumerate() {
            let again = list.iter().skip(i + 1).any(|w| w == v);
            if again && !out.contains(v) {
                out.push(v.clone());
            }
        }
    }
    out
}

/// The call's arguments, a method call's receiver first, as values.
fn all_args(f: &FunctionContext<'_, '_>) -> Vec<Value> {
    f.this
        .iter()
        .chain(f.args.iter())
        .map(|v| Value::try_from(v.as_ref()).unwrap_or(Value::Null))
        .collect()
}

fn args<const N: usize>(f: &FunctionContext<'_, '_>, name: &str) -> Result<[Value; N], ExecutionError> {
    let all = all_args(f);
    let got = all.len();
    <[Value; N]>::try_from(all).map_err(|_| fail(name, format!("expects {N} argument(s), got {got}")))
}

fn fail(name: &str, message: impl ToString) -> ExecutionError {
    ExecutionError::function_error(name, message)
}

fn type_name(v: &Value) -> String {
    v.type_of().to_string()
}

fn as_list(v: &Value, name: &str) -> Result<Arc<Vec<Value>>, ExecutionError> {
    match v {
        Value::List(l) => Ok(Arc::clone(l)),
        other => Err(fail(name, format!("expects a list, got {}", type_name(other)))),
    }
}

fn as_int(v: &Value, name: &str) -> Result<i64, ExecutionError> {
    match v {
        Value::Int(i) => Ok(*i),
        Value::UInt(u) => i64::try_from(*u).map_err(|_| fail(name, format!("{u} is too large"))),
        other => Err(fail(name, format!("expects an int, got {}", type_name(other)))),
    }
}

/// An int as its 64-bit two's complement pattern, so `bit(-1, 63)` is true.
fn as_bits(v: &Value, name: &str) -> Result<u64, ExecutionError> {
    match v {
        Value::UInt(u) => Ok(*u),
        other => as_int(other, name).map(|i| i as u64),
    }
}

/// An object index; `None` when the int is no 16-bit index (no object has it).
fn as_index(v: &Value, name: &str) -> Result<Option<u16>, ExecutionError> {
    as_int(v, name).map(|i| u16::try_from(i).ok())
}

fn as_sub(v: &Value, name: &str) -> Result<Option<u8>, ExecutionError> {
    as_int(v, name).map(|i| u8::try_from(i).ok())
}

/// A number compared across ints, uints and doubles without losing 64-bit precision.
#[derive(Debug, Clone, Copy)]
enum Number {
    Int(i128),
    Float(f64),
}

impl Number {
    fn le(&self, other: &Number) -> bool {
        match (*self, *other) {
            (Number::Int(a), Number::Int(b)) => a <= b,
            (Number::Int(a), Number::Float(b)) => (a as f64) <= b,
            (Number::Float(a), Number::Int(b)) => a <= b as f64,
            (Number::Float(a), Number::Float(b)) => a <= b,
        }
    }
}

fn as_number(v: &Value) -> Result<Number, ExecutionError> {
    match v {
        Value::Int(i) => Ok(Number::Int(i128::from(*i))),
        Value::UInt(u) => Ok(Number::Int(i128::from(*u))),
        Value::Float(f) => Ok(Number::Float(*f)),
        other => Err(fail(
            "in_range",
            format!("expects numbers, got {}", type_name(other)),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(expression: &str) -> Result<Value, ExecutionError> {
        let env = Arc::new(environment());
        let mut ctx = cel::Context::with_env(Arc::clone(&env));
        let mut file = FileIndex {
            node_id: 5,
            ..FileIndex::default()
        };
        let item = |name: &str| {
            Value::Map(
                HashMap::from([
                    ("name".to_owned(), Value::from(name)),
                    (
                        "keys".to_owned(),
                        Value::Map(HashMap::from([("ParameterName".to_owned(), Value::from(name))]).into()),
                    ),
                ])
                .into(),
            )
        };
        let objects = vec![item("Identity"), item("Count"), item("Vendor")];
        file.positions.insert((0x1018, None), 0);
        file.positions.insert((0x1018, Some(0)), 1);
        file.positions.insert((0x1018, Some(1)), 2);
        file.subs.insert(0x1018, vec![0, 1]);
        let eds = Value::Map(HashMap::from([("objects".to_owned(), Value::List(Arc::new(objects)))]).into());
        let eds: Box<dyn cel::common::value::Val> = eds.try_into()?;
        ctx.add_variable_as_val(EDS_VAR, eds);
        install(&mut ctx, &Arc::new(file));
        let program = env
            .compile(expression)
            .map_err(|e| ExecutionError::InternalError(e.to_string()))?;
        program.execute(&ctx)
    }

    fn truth(expression: &str) -> bool {
        run(expression) == Ok(Value::Bool(true))
    }

    #[test]
    fn uniqueness_and_counts() {
        assert!(truth("unique([1, 2, 3]) && !unique([1, 2, 1])"));
        assert!(truth("unique([]) && unique(['a', 'A'])"));
        assert!(truth("duplicates(['a', 'b', 'a', 'c', 'b', 'a']) == ['a', 'b']"));
        assert!(
            truth("duplicates([1, 1u, 2]) == [1u]"),
            "ints and uints are equal in CEL"
        );
        assert!(
            truth("duplicates([[1], [2], [1]]) == [[1]]"),
            "lists compare by value"
        );
        assert!(truth("count([1, 2, 1], 1) == 2 && count([], 'x') == 0"));
        assert!(
            truth("[1, 2, 2].unique() == false"),
            "method form takes the receiver first"
        );
        assert!(run("unique(1)").is_err());
        assert!(run("count([1])").is_err());
    }

    #[test]
    fn bit_tests() {
        assert!(truth("bit(0x80000000, 31) && !bit(0x80000000, 30)"));
        assert!(truth("bit(-1, 63)"), "negative ints are two's complement");
        assert!(truth(
            "bits(0x40000180, 0, 11) == 0x180 && bits(0x40000180, 30, 2) == 1"
        ));
        assert!(truth("bits(-1, 0, 64) == -1 && bits(5u, 0, 2) == 1"));
        assert!(run("bit(1, 64)").is_err());
        assert!(run("bit(1, -1)").is_err());
        assert!(run("bits(1, 60, 5)").is_err());
        assert!(run("bits(1, 0, 0)").is_err());
        assert!(run("bit('1', 0)").is_err());
    }

    #[test]
    fn ranges_mix_number_types() {
        assert!(truth(
            "in_range(5, 1, 10) && in_range(1, 1, 1) && !in_range(11, 1, 10)"
        ));
        assert!(truth(
            "in_range(2.5, 1, 3) && in_range(3u, 1, 3.0) && !in_range(-1, 0u, 1u)"
        ));
        assert!(truth("in_range(9223372036854775807, 0, 18446744073709551615u)"));
        assert!(run("in_range(null, 0, 1)").is_err());
        assert!(run("in_range('1', 0, 1)").is_err());
    }

    #[test]
    fn eds_numbers() {
        assert!(truth(
            "number('0x80') == 128 && number('128') == 128 && number('0200') == 128"
        ));
        assert!(truth(
            "number(' $NODEID+0x180 ') == 0x185 && number('$nodeid') == 5"
        ));
        assert!(truth("number('0x180+$NODEID') == 0x185"));
        assert!(truth(
            "number('-5') == -5 && number(7) == 7 && number(null) == null"
        ));
        assert!(truth(
            "number('') == null && number('abc') == null && number('$NODEID+$NODEID') == null"
        ));
        assert!(truth("number('0xFFFFFFFFFFFFFFFF') == null"), "beyond int64");
        assert!(run("number(1.5)").is_err());
        assert_eq!(eds_number("0x10", 1), Some(16));
        assert_eq!(eds_number("$NODEID+2", 127), Some(129));
    }

    #[test]
    fn hex_and_replace() {
        assert!(truth(
            "hex(0x1A) == '0x1A' && hex(0x1A, 4) == '0x001A' && hex(0, 2) == '0x00'"
        ));
        assert!(truth("hex(-16) == '-0x10'"));
        assert!(truth(
            "replace('a b c', ' ', '_') == 'a_b_c' && 'a b'.replace(' ', '-') == 'a-b'"
        ));
        assert!(run("replace('a', '', 'x')").is_err());
        assert!(run("hex('1')").is_err());
        assert!(run("hex(1, 2, 3)").is_err());
    }

    #[test]
    fn lookups_in_the_file() {
        assert!(truth(
            "has_object(0x1018) && !has_object(0x1000) && !has_object(70000)"
        ));
        assert!(truth(
            "has_sub(0x1018, 1) && !has_sub(0x1018, 2) && !has_sub(0x1018, 300)"
        ));
        assert!(truth(
            "object(0x1018).name == 'Identity' && object(0x2000) == null"
        ));
        assert!(truth("sub(0x1018, 1).name == 'Vendor' && sub(0x1018, 9) == null"));
        assert!(truth(
            "subs(0x1018).map(s, s.name) == ['Count', 'Vendor'] && subs(0x1000) == []"
        ));
        assert!(truth("key(object(0x1018), 'parametername') == 'Identity'"));
        assert!(truth("key(object(0x1018), 'DefaultValue') == null"));
        assert!(run("key(1, 'x')").is_err());
        assert!(run("object('0x1018')").is_err());
    }

    #[test]
    fn extensions_are_available() {
        assert!(truth(
            "'AbC'.lowerAscii() == 'abc' && 'a,b'.split(',') == ['a', 'b']"
        ));
        assert!(truth("math.bitAnd(6, 3) == 2 && [3, 1, 2].sort() == [1, 2, 3]"));
        assert!(truth("'ab1'.matches('^[a-z]+[0-9]$')"));
    }
}
