//! Arbitrary text as a rule pack: parsing must never panic (errors are `PackError`s), and a pack that
//! parses must run on a small EDS without panicking.

#![no_main]

use canopener_check::{Context, Selection};
use libfuzzer_sys::fuzz_target;

const EDS: &str = "[FileInfo]\nFileName=f.eds\n[DeviceInfo]\nVendorNumber=1\n[MandatoryObjects]\n\
SupportedObjects=1\n1=0x1000\n[1000]\nParameterName=Device type\nDataType=0x0007\nAccessType=ro\n\
DefaultValue=0x191\n";

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(pack) = canopener_rules::parse_pack(text, "fuzz.toml") else {
        return;
    };
    let loaded = canopener_eds::load(EDS.as_bytes());
    let cx = Context::new(&loaded, Some("f.eds"));
    let selection = Selection::default();
    let _ = pack.check(&cx, &selection);
    let _ = pack.fixes(&cx, &selection);
});
