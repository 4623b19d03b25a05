//! The rule pack format: what a pack may say, the errors it gets when it says something wrong (with
//! line and column), structured assertions, templates, lets, fixes and `R000`.

use canopener_check::fix::{self, Edit};
use canopener_check::{Context, Finding, Selection};
use canopener_eds::Severity;
use canopener_rules::{PackError, PackErrorKind, RulePack, parse_pack};

const FILE: &str = "\
[FileInfo]
FileName=f.eds
[DeviceInfo]
VendorNumber=0x10
BaudRate_250=1
[1000]
ParameterName=Device type
DataType=0x0007
AccessType=ro
DefaultValue=0x191
[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=2
[1018sub0]
ParameterName=Count
DataType=0x0005
AccessType=ro
DefaultValue=1
[1018sub1]
ParameterName=Vendor
DataType=0x0007
AccessType=ro
DefaultValue=0x10
[1400sub1]
ParameterName=COB-ID
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x200
[2000]
ParameterName=Gains
ObjectType=0x8
DataType=0x0003
AccessType=rw
CompactSubObj=3
DefaultValue=7
";

/// A pack of one rule: `[pack]` then `[[rule]]` with the given body.
fn one_rule(body: &str) -> String {
    format!("[pack]\nname = \"t\"\n\n[[rule]]\n{body}")
}

fn parsed(text: &str) -> RulePack {
    parse_pack(text, "t.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn error(text: &str) -> PackError {
    match parse_pack(text, "t.toml") {
        Ok(_) => panic!("the pack parsed:\n{text}"),
        Err(e) => e,
    }
}

fn run(pack: &RulePack, text: &str) -> Vec<Finding> {
    let loaded = canopener_eds::load(text.as_bytes());
    let cx = Context::new(&loaded, Some("f.eds"));
    pack.check(&cx, &Selection::default())
}

fn sections(findings: &[Finding]) -> Vec<String> {
    findings
        .iter()
        .map(|f| f.diagnostic.section.clone().unwrap_or_default())
        .collect()
}

const HEAD: &str = "id = \"t/r\"\ndescription = \"d\"\nseverity = \"warning\"\n";

// --- Errors -----------------------------------------------------------------------------------

#[test]
fn toml_errors_name_line_and_column() {
    let e = error("[pack]\nname = \"t\"\n[[rule]\nid = 1\n");
    assert_eq!(e.diagnostic.code, PackErrorKind::Toml);
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (3, 8));
    assert!(e.to_string().starts_with("t.toml:3:8: "), "{e}");
    assert!(e.to_string().contains("\n  help: "), "{e}");

    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\nsevrity = \"x\"\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::Toml);
    assert_eq!(e.diagnostic.span.line, 10);
    assert!(
        e.diagnostic.message.contains("unknown field `sevrity`"),
        "{}",
        e.diagnostic.message
    );

    let e = error(&one_rule(
        "id = \"t/r\"\ndescription = \"d\"\nseverity = \"warning\"\nselect = \"objects\"\n",
    ));
    assert!(
        e.diagnostic.message.contains("missing field `assert`"),
        "{}",
        e.diagnostic.message
    );

    let e = error(&format!("[[rule]]\n{HEAD}select = \"file\"\nassert = \"true\"\n"));
    assert!(
        e.diagnostic.message.contains("missing field `pack`"),
        "{}",
        e.diagnostic.message
    );
}

#[test]
fn ids_are_namespaced_and_unique() {
    let e = error(&one_rule(
        "id = \"norule\"\ndescription = \"d\"\nseverity = \"info\"\nselect = \"file\"\nassert = \"true\"\n",
    ));
    assert_eq!(e.diagnostic.code, PackErrorKind::InvalidId);
    assert_eq!(e.rule.as_deref(), Some("norule"));
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (5, 7));
    for bad in ["a/", "/a", "a/b c", "a//b", "C301", "a/-b"] {
        let text = one_rule(&format!(
            "id = \"{bad}\"\ndescription = \"d\"\nseverity = \"info\"\nselect = \"file\"\nassert = \"true\"\n"
        ));
        assert_eq!(error(&text).diagnostic.code, PackErrorKind::InvalidId, "{bad}");
    }
    let rule = format!("{HEAD}select = \"file\"\nassert = \"true\"\n");
    let twice = format!("{}\n[[rule]]\n{}", one_rule(&rule), rule.replace("t/r", "T/R"));
    let e = error(&twice);
    assert_eq!(e.diagnostic.code, PackErrorKind::DuplicateId);
    assert_eq!(e.diagnostic.span.line, 11);
    assert_eq!(
        e.diagnostic.message,
        "the id is already used by the rule on line 4"
    );
    assert!(
        parsed(&one_rule(&rule.replace("t/r", "team.a/sub-x/rule_1"))).rule_ids() == ["team.a/sub-x/rule_1"]
    );
}

#[test]
fn severity_and_select_are_checked() {
    let e = error(&one_rule(
        "id = \"t/r\"\ndescription = \"d\"\nseverity = \"fatal\"\nselect = \"file\"\nassert = \"true\"\n",
    ));
    assert_eq!(e.diagnostic.code, PackErrorKind::Severity);
    assert_eq!(
        (
            e.diagnostic.span.line,
            e.diagnostic.span.column,
            e.diagnostic.message.as_str()
        ),
        (7, 13, "unknown severity `fatal`")
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"object\"\nassert = \"true\"\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::Select);
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (8, 11));
    assert_eq!(
        e.to_string(),
        "t.toml:8:11: rule `t/r`: unknown select `object`\n  help: select one of \"file\" (once per file), \"objects\", \"subobjects\" or \"entries\" (objects and sub-objects)"
    );
}

#[test]
fn cel_syntax_errors_point_into_the_expression() {
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"item.name ==\"\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::CelSyntax);
    // `assert = "` is 10 characters; the expression's end is its 13th column.
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (9, 23));
    assert!(
        e.diagnostic
            .message
            .starts_with("in assert: CEL syntax error in `item.name ==`"),
        "{}",
        e.diagnostic.message
    );

    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = '''\ntrue &&\n  item.index >\n'''\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::CelSyntax);
    assert_eq!(e.diagnostic.span.line, 12, "{e}");
}

#[test]
fn unknown_names_are_errors_with_suggestions() {
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"itme.index > 0\"\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::UnknownName);
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (9, 11));
    assert_eq!(
        e.to_string(),
        "t.toml:9:11: rule `t/r`: in assert `itme.index > 0`: unknown variable `itme`\n  help: did you mean `item`? rules can use `eds`, `params`, `item`"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nwhere = \"item.idx > 0\"\nassert = \"true\"\n"
    )));
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (9, 14));
    assert_eq!(
        e.diagnostic.message,
        "in where `item.idx > 0`: unknown field `item.idx`"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"has_objekt(1)\"\n"
    )));
    assert_eq!(e.diagnostic.help.as_deref(), Some("did you mean `has_object`?"));
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"file\"\nassert = \"item.index > 0\"\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "in assert `item.index > 0`: `item` does not exist here: a rule with select = \"file\" is evaluated once per file"
    );
}

#[test]
fn parameters_are_typed() {
    let rule = |params: &str| {
        one_rule(&format!(
            "{HEAD}select = \"file\"\nassert = \"true\"\n[rule.params]\n{params}\n"
        ))
    };
    let e = error(&rule("rates = { type = \"list<int>\", value = [125, \"250\"] }"));
    assert_eq!(e.diagnostic.code, PackErrorKind::Parameter);
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (11, 39));
    assert_eq!(
        e.diagnostic.message,
        "parameter `rates` is declared `list<int>` but element 2 is a string (expected int)"
    );
    let e = error(&rule("n = { type = \"int\", value = \"1\" }"));
    assert_eq!(
        e.diagnostic.message,
        "parameter `n` is declared `int` but its value is a string"
    );
    let e = error(&rule("n = { type = \"integer\", value = 1 }"));
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (11, 15));
    assert!(
        e.diagnostic
            .help
            .as_deref()
            .is_some_and(|h| h.contains("list<string>")),
        "{:?}",
        e.diagnostic.help
    );
    let e = error(&rule("n = { type = \"list<int>\", value = 1 }"));
    assert_eq!(
        e.diagnostic.message,
        "parameter `n` is declared `list<int>` but its value is a integer"
    );
    let e = error(&rule("n = { type = \"int\" }"));
    assert!(
        e.diagnostic.message.contains("missing field `value`"),
        "{}",
        e.diagnostic.message
    );
    let e = error(&rule("\"my name\" = { type = \"int\", value = 1 }"));
    assert_eq!(e.diagnostic.message, "`my name` cannot be a parameter name");
    // Every type, including an integer where a double is declared.
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"file\"\nassert = \"params.i == 1 && params.d == 2.0 && params.b && params.s == 'x' && \
         params.li == [1] && params.ld == [1.5, 2.0] && params.lb == [true] && params.ls == ['a']\"\n\
         [rule.params]\ni = {{ type = \"int\", value = 1 }}\nd = {{ type = \"double\", value = 2 }}\n\
         b = {{ type = \"bool\", value = true }}\ns = {{ type = \"string\", value = \"x\" }}\n\
         li = {{ type = \"list<int>\", value = [1] }}\nld = {{ type = \"list< double >\", value = [1.5, 2] }}\n\
         lb = {{ type = \"list<bool>\", value = [true] }}\nls = {{ type = \"list<string>\", value = [\"a\"] }}\n"
    )));
    assert!(run(&pack, FILE).is_empty());
    let described = pack.describe();
    assert!(
        described[0]
            .explanation
            .contains("ld (list< double >) = [1.5, 2]"),
        "{}",
        described[0].explanation
    );
    // An undeclared parameter is an unknown name.
    let e = error(
        &rule("n = { type = \"int\", value = 1 }").replace("assert = \"true\"", "assert = \"params.m > 0\""),
    );
    assert_eq!(
        e.diagnostic.message,
        "in assert `params.m > 0`: unknown parameter `params.m`"
    );
    assert_eq!(
        e.diagnostic.help.as_deref(),
        Some("did you mean `n`? `params` has `n`")
    );
}

#[test]
fn malformed_structured_assertions_and_templates() {
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"file\"\n[rule.assert]\nall = []\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::Assertion);
    assert_eq!(e.diagnostic.message, "assert.all is empty");
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"file\"\n[rule.assert]\nall = [\"true\"]\nany = [\"true\"]\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "assert has 2 keys (all, any); it needs exactly one of all, any, not"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"file\"\n[rule.assert]\nnone = [\"true\"]\n"
    )));
    assert_eq!(e.diagnostic.message, "assert has the unknown key `none`");
    let e = error(&one_rule(&format!("{HEAD}select = \"file\"\nassert = 5\n")));
    assert_eq!(e.diagnostic.message, "assert is a integer");
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"file\"\n[rule.assert]\nall = [\"true\", {{ not = \"eds.nope\" }}]\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::UnknownName);
    assert_eq!(
        e.diagnostic.message,
        "in assert.all[1].not `eds.nope`: unknown field `eds.nope`"
    );
    assert_eq!(
        (e.diagnostic.span.line, e.diagnostic.span.column),
        (10, 28),
        "nested expressions are located in the table"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\nmessage = \"name {{item.name\"\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::Template);
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (10, 17));
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\nhelp = \"{{item.nam}}\"\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "in help `item.nam`: unknown field `item.nam`"
    );
    assert_eq!((e.diagnostic.span.line, e.diagnostic.span.column), (10, 14));
}

#[test]
fn fixes_and_places_must_fit_the_selection() {
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\n[rule.fix]\nvalue = \"'x'\"\nchanges_meaning = false\n"
    )));
    assert_eq!(e.diagnostic.code, PackErrorKind::Fix);
    assert_eq!(e.diagnostic.message, "the fix needs the key it sets");
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\n[rule.fix]\nkey = \"K\"\nvalue = \"'x'\"\n"
    )));
    assert!(
        e.diagnostic.message.contains("missing field `changes_meaning`"),
        "{}",
        e.diagnostic.message
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\n[rule.fix]\nsection = \"DeviceInfo\"\nkey = \"K\"\nvalue = \"'x'\"\nchanges_meaning = false\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "a fix of an object rule edits the item's own section"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"file\"\nassert = \"true\"\n[rule.fix]\nkey = \"K\"\nvalue = \"'x'\"\nchanges_meaning = false\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "a fix of a file rule needs the section it edits"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nsection = \"DeviceInfo\"\nassert = \"true\"\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "`section` is only for select = \"file\" rules"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"file\"\nsection = \"Nonsense Section\"\nassert = \"true\"\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "`Nonsense Section` is not a CiA 306 section name"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\n[rule.let]\nitem = \"1\"\n"
    )));
    assert_eq!(
        e.diagnostic.message,
        "the let binding `item` hides the variable of that name"
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\n[rule.let]\nx = \"item.index\"\n"
    )));
    assert!(
        e.diagnostic
            .message
            .starts_with("in let.x `item.index`: `item` does not exist here"),
        "{}",
        e.diagnostic.message
    );
    let e = error(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"true\"\n[rule.let]\nx = \"1\"\ny = \"x + 1\"\n"
    )));
    assert_eq!(
        e.diagnostic.message, "in let.y `x + 1`: unknown variable `x`",
        "lets cannot see each other"
    );
}

// --- Evaluation -------------------------------------------------------------------------------

#[test]
fn selections_pick_objects_sub_objects_entries_or_the_file() {
    let rule = |select: &str, extra: &str| {
        parsed(&one_rule(&format!(
            "{HEAD}select = \"{select}\"\nassert = \"false\"\n{extra}"
        )))
    };
    assert_eq!(
        sections(&run(&rule("objects", ""), FILE)),
        ["1000", "1018", "2000"]
    );
    assert_eq!(
        sections(&run(&rule("subobjects", ""), FILE)),
        ["1018sub0", "1018sub1", "1400sub1"]
    );
    assert_eq!(run(&rule("entries", ""), FILE).len(), 6);
    // Generated items: the orphan object 1400 and the compact sub-objects of 2000, pointing at the
    // section they come from.
    let all = run(&rule("entries", "include_generated = true\n"), FILE);
    assert_eq!(all.len(), 11);
    let generated: Vec<_> = all
        .iter()
        .filter(|f| !f.fixable)
        .map(|f| f.diagnostic.section.clone().unwrap_or_default())
        .collect();
    assert!(generated.contains(&"2000sub3".to_owned()), "{generated:?}");
    let file = run(&rule("file", ""), FILE);
    assert_eq!(file.len(), 1);
    assert_eq!(
        (
            file[0].diagnostic.span.line,
            file[0].diagnostic.section.as_deref()
        ),
        (1, None)
    );
    let at = run(
        &rule("file", "section = \"[DeviceInfo]\"\nkey = \"BaudRate_250\"\n"),
        FILE,
    );
    assert_eq!(
        (at[0].diagnostic.span.line, at[0].diagnostic.span.column),
        (5, 14)
    );
    assert_eq!(
        (
            at[0].diagnostic.section.as_deref(),
            at[0].diagnostic.key.as_deref()
        ),
        (Some("DeviceInfo"), Some("BaudRate_250"))
    );
}

#[test]
fn structured_assertions_nest_all_any_and_not() {
    let pack = |assert: &str| {
        parsed(&one_rule(&format!(
            "{HEAD}select = \"subobjects\"\nwhere = \"item.index == 0x1018\"\n[rule.assert]\n{assert}\n"
        )))
    };
    let messages = |assert: &str| {
        run(&pack(assert), FILE)
            .into_iter()
            .map(|f| f.diagnostic.message)
            .collect::<Vec<_>>()
    };
    // sub0 (value 1) and sub1 (value 0x10)
    assert_eq!(
        messages("all = [\"item.value > 0\", \"item.value < 2\"]"),
        ["d (failed: `item.value < 2`)"]
    );
    assert!(messages("any = [\"item.value == 1\", \"item.value == 0x10\"]").is_empty());
    assert_eq!(
        messages("any = [\"item.value == 1\", \"item.sub == 0\"]"),
        ["d (failed: none of `item.value == 1`, `item.sub == 0`)"]
    );
    assert_eq!(
        messages("not = \"item.sub == 0\""),
        ["d (failed: not `item.sub == 0`)"]
    );
    assert_eq!(
        messages(
            "all = [\"true\", { any = [\"false\", { not = { all = [\"item.sub == 1\", \"true\"] } }] }]"
        ),
        ["d (failed: none of `false`, not all of (`item.sub == 1`, `true`))"]
    );
    // `any` holds when one member holds even if another cannot be evaluated.
    assert!(messages("any = [\"item.name > 3\", \"true\"]").is_empty());
    let found = run(&pack("any = [\"item.name > 3\", \"false\"]"), FILE);
    assert_eq!(
        found
            .iter()
            .map(|f| f.diagnostic.code.as_str())
            .collect::<Vec<_>>(),
        ["R000"]
    );
}

#[test]
fn templates_show_values_and_keep_literal_braces() {
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"subobjects\"\nwhere = \"item.index == 0x1018 && item.sub == 1\"\nassert = \"false\"\n\
         message = \"{{{{{{item.name}}}}}} {{hex(item.value, 4)}} {{[item.sub, 'x', null]}} {{ {{'k': 1}}.k }} {{item.value > 1}}\"\n\
         help = \"set {{item.section}}\"\n"
    )));
    let found = run(&pack, FILE);
    assert_eq!(
        found[0].diagnostic.message,
        "{Vendor} 0x0010 [1, \"x\", null] 1 true"
    );
    assert_eq!(found[0].diagnostic.help.as_deref(), Some("set 1018sub1"));
}

#[test]
fn lets_are_computed_once_and_see_params_and_eds() {
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nassert = \"item.index in wanted\"\nmessage = \"{{hex(item.index, 4)}} not in {{wanted.map(i, hex(i, 4))}}\"\n\
         [rule.params]\nextra = {{ type = \"int\", value = 0x2000 }}\n\
         [rule.let]\nwanted = \"eds.objects.filter(o, o.sub == null && o.name.startsWith('D')).map(o, o.index) + [params.extra]\"\n"
    )));
    let found = run(&pack, FILE);
    assert_eq!(
        found
            .iter()
            .map(|f| f.diagnostic.message.as_str())
            .collect::<Vec<_>>(),
        ["0x1018 not in [\"0x1000\", \"0x2000\"]"]
    );
}

#[test]
fn the_library_sees_the_file() {
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"file\"\n[rule.assert]\nall = [\n\
         \"has_object(0x1018) && !has_object(0x1400) == false && !has_object(0x1001)\",\n\
         \"has_sub(0x1018, 1) && !has_sub(0x1018, 2)\",\n\
         \"object(0x1018).name == 'Identity' && object(0x6000) == null\",\n\
         \"sub(0x1018, 1).value == 0x10 && sub(0x1400, 1).value == 0x201 && sub(0x1400, 1).nodeid_relative\",\n\
         \"subs(0x1018).map(s, s.name) == ['Count', 'Vendor'] && subs(0x2000).size() == 4\",\n\
         \"number(eds.device_info.VendorNumber) == 16 && number('$NODEID+1') == eds.node_id + 1\",\n\
         \"key(object(0x1000), 'defaultvalue') == '0x191' && object(0x1000).keys.DefaultValue == '0x191'\",\n\
         \"unique(eds.objects.filter(o, o.sub == null).map(o, o.index)) && count(eds.objects.map(o, o.index), 0x1018) == 3\",\n\
         \"bit(object(0x1000).value, 0) && bits(object(0x1000).value, 4, 4) == 9 && in_range(object(0x1000).value, 0, 0x200)\",\n\
         \"object(0x2000).object_type == 'ARRAY' && sub(0x2000, 2).origin == 'compact-sub-obj' && !sub(0x2000, 2).written\",\n\
         \"sub(0x2000, 2).value == 7 && sub(0x2000, 2).data_type_name == 'INTEGER16' && object(0x1018) == object(0x1018)\",\n\
         \"eds.objects.exists(o, o == sub(0x1018, 1)) && eds.file_name == 'f.eds' && !eds.is_dcf\",\n\
         \"[1].exists(eds, object(0x1018) != null)\",\n\
         ]\n"
    )));
    assert_eq!(run(&pack, FILE), Vec::<Finding>::new());
    // In a DCF `$NODEID` is the commissioned node.
    let dcf = format!("{FILE}[DeviceComissioning]\nNodeID=5\n");
    let node = parsed(&one_rule(&format!(
        "{HEAD}select = \"file\"\nassert = \"sub(0x1400, 1).value == 0x205 && number('$NODEID') == 5 && eds.is_dcf\"\n"
    )));
    assert_eq!(run(&node, &dcf), Vec::<Finding>::new());
}

#[test]
fn a_runtime_error_is_one_r000_per_rule_and_file() {
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"entries\"\ninclude_generated = true\nassert = \"item.value > 0\"\n"
    )));
    // `value` is null for the record 1018 and the placeholder object of the orphan 1400sub1 (no
    // DefaultValue): comparing null with 0 fails on each.
    let found = run(&pack, FILE);
    let r000: Vec<_> = found.iter().filter(|f| f.diagnostic.code == "R000").collect();
    assert_eq!(r000.len(), 1);
    assert_eq!(r000[0].diagnostic.severity, Severity::Error);
    assert_eq!(r000[0].diagnostic.section.as_deref(), Some("1018"));
    assert_eq!(r000[0].diagnostic.span.line, 11);
    assert!(
        r000[0].diagnostic.message.starts_with("rule `t/r` could not be evaluated on [1018] (and 1 more item): assert: `item.value > 0`: found no matching overload for '_>_' applied to '(null_type, int)' (a value is null: test it with `!= null` first)"),
        "{}",
        r000[0].diagnostic.message
    );
    assert!(
        r000[0]
            .diagnostic
            .help
            .as_deref()
            .is_some_and(|h| h.contains("--skip t/r"))
    );
    // The other items are still checked, and the rule's own findings still reported.
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"entries\"\nassert = \"item.value > 1\"\n"
    )));
    let codes: Vec<_> = run(&pack, FILE).into_iter().map(|f| f.diagnostic.code).collect();
    assert_eq!(codes.iter().filter(|c| *c == "t/r").count(), 1, "{codes:?}");
    // `--skip R000` hides them.
    let loaded = canopener_eds::load(FILE.as_bytes());
    let cx = Context::new(&loaded, None);
    let skip = Selection {
        skip: vec!["r000".to_owned()],
        ..Selection::default()
    };
    assert!(pack.check(&cx, &skip).iter().all(|f| f.diagnostic.code != "R000"));
}

#[test]
fn every_part_of_a_rule_can_fail_at_run_time() {
    let cases = [
        (
            "where = \"item.name\"\nassert = \"true\"\n",
            "where: `item.name` gave a string where a bool is needed",
        ),
        (
            "assert = \"item.keys.Missing == 'x'\"\n",
            "assert: `item.keys.Missing == 'x'`: no such key `Missing`",
        ),
        (
            "assert = \"false\"\nmessage = \"{1 / (item.index - item.index)}\"\n",
            "message: `1 / (item.index - item.index)`: ",
        ),
        (
            "assert = \"false\"\nhelp = \"{bit(1, 99)}\"\n",
            "help: `bit(1, 99)`: Error executing function 'bit': bit number 99 is outside 0..=63",
        ),
        (
            "assert = \"false\"\n[rule.fix]\nkey = \"X\"\nvalue = \"item.index\"\nchanges_meaning = false\n",
            "fix.value: gave a int where a string is needed",
        ),
        (
            "assert = \"true\"\n[rule.let]\nv = \"eds.device_info.Nope\"\n",
            "let.v: no such key `Nope`",
        ),
    ];
    for (body, expected) in cases {
        let pack = parsed(&one_rule(&format!("{HEAD}select = \"objects\"\n{body}")));
        let found = run(&pack, FILE);
        assert_eq!(found.len(), 1, "{body}: {found:#?}");
        assert_eq!(found[0].diagnostic.code, "R000");
        assert!(
            found[0].diagnostic.message.contains(expected),
            "{body}: {}",
            found[0].diagnostic.message
        );
    }
}

#[test]
fn fixes_set_or_add_keys_and_file_rules_add_sections() {
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nwhere = \"item.index == 0x1000\"\nassert = \"key(item, 'Unit') == 'mm'\"\n\
         [rule.fix]\nkey = \"Unit\"\nvalue = \"'mm'\"\nchanges_meaning = true\n"
    )));
    let loaded = canopener_eds::load(FILE.as_bytes());
    let cx = Context::new(&loaded, None);
    let planned = pack.fixes(&cx, &Selection::default());
    assert_eq!(planned.len(), 1);
    assert_eq!(planned[0].description, "[1000] add Unit=mm");
    assert_eq!(
        planned[0].edits,
        [Edit::AppendEntry {
            section: 2,
            key: "Unit".to_owned(),
            value: "mm".to_owned()
        }]
    );
    let found = pack.check(&cx, &Selection::default());
    assert!(found[0].fixable);
    assert_eq!(
        found[0].diagnostic.key.as_deref(),
        Some("Unit"),
        "a finding points at the fix's key"
    );
    let fixed = fix::apply(&loaded.document, &planned).document;
    let text = String::from_utf8(fixed.to_bytes().unwrap_or_default()).unwrap_or_default();
    assert!(text.contains("DefaultValue=0x191\nUnit=mm\n[1018]"), "{text}");

    // A value that would not change, or could not be written, is no fix.
    let same = parsed(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nwhere = \"item.index == 0x1000\"\nassert = \"false\"\n\
         [rule.fix]\nkey = \"DefaultValue\"\nvalue = \"item.default\"\nchanges_meaning = false\n"
    )));
    assert!(same.fixes(&cx, &Selection::default()).is_empty());
    assert!(!same.check(&cx, &Selection::default())[0].fixable);
    let multiline = parsed(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nwhere = \"item.index == 0x1000\"\nassert = \"false\"\n\
         [rule.fix]\nkey = \"DefaultValue\"\nvalue = \"'a\\\\nb'\"\nchanges_meaning = false\n"
    )));
    assert!(multiline.fixes(&cx, &Selection::default()).is_empty());

    // A file rule edits its section, or adds it.
    let file_rule = |section: &str| {
        parsed(&one_rule(&format!(
            "{HEAD}select = \"file\"\nsection = \"{section}\"\nassert = \"false\"\n\
             [rule.fix]\nkey = \"BaudRate_500\"\nvalue = \"'1'\"\nchanges_meaning = true\n"
        )))
    };
    let planned = file_rule("DeviceInfo").fixes(&cx, &Selection::default());
    assert_eq!(planned[0].description, "[DeviceInfo] add BaudRate_500=1");
    let planned = file_rule("Comments").fixes(&cx, &Selection::default());
    assert_eq!(planned[0].description, "add [Comments] with BaudRate_500=1");
    assert_eq!(
        planned[0].edits,
        [Edit::AppendLines {
            lines: vec!["[Comments]".to_owned(), "BaudRate_500=1".to_owned()]
        }]
    );
    // Generated items have no section to edit.
    let generated = parsed(&one_rule(&format!(
        "{HEAD}select = \"subobjects\"\ninclude_generated = true\nwhere = \"item.index == 0x2000\"\nassert = \"false\"\n\
         [rule.fix]\nkey = \"DefaultValue\"\nvalue = \"'1'\"\nchanges_meaning = true\n"
    )));
    assert!(generated.fixes(&cx, &Selection::default()).is_empty());
    assert_eq!(generated.check(&cx, &Selection::default()).len(), 4);
}

#[test]
fn an_empty_pack_is_fine_and_the_default_explanation_describes_the_rule() {
    let empty = parsed("[pack]\nname = \"empty\"\ndescription = \"nothing\"\n");
    assert!(empty.rule_ids().is_empty());
    assert_eq!(
        (
            empty.name.as_str(),
            empty.description.as_str(),
            empty.origin.as_str()
        ),
        ("empty", "nothing", "t.toml")
    );
    assert!(run(&empty, FILE).is_empty());
    let pack = parsed(&one_rule(&format!(
        "{HEAD}select = \"objects\"\nwhere = \"item.index >= 0x2000\"\nassert = \"!item.name.contains(' ')\"\nspec = \"handbook §2\"\n"
    )));
    let d = &pack.describe()[0];
    assert_eq!(d.spec, "handbook §2");
    assert_eq!(
        d.explanation,
        "d.\n\nChecks every object written in the file where `item.index >= 0x2000`: `!item.name.contains(' ')`.\n\n\
         A user rule from the pack `t` (t.toml), reported as a warning."
    );
    let e = error("[pack]\nname = \" \"\n");
    assert_eq!(e.diagnostic.message, "the pack's `name` is empty");
}
