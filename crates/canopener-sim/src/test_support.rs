//! Descriptions and helpers the simulator's unit tests share.

use std::path::{Path, PathBuf};

use canopener_can::CanFrame;
use canopener_testkit::fixture::ScratchDir;

/// A consumer heartbeat time 1016h with one entry, off.
pub(crate) const CONSUMER_1016: &str = "\n[1016]\nParameterName=Consumer heartbeat time\nObjectType=0x8\n\
    SubNumber=2\n\n[1016sub0]\nParameterName=Number of entries\nObjectType=0x7\nDataType=0x0005\n\
    AccessType=ro\nDefaultValue=1\nPDOMapping=0\n\n[1016sub1]\nParameterName=Consumer heartbeat time 1\n\
    ObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0\nPDOMapping=0\n";

/// COB-ID TIME 1012h, consumer and producer off.
pub(crate) const TIME_1012: &str = "\n[1012]\nParameterName=COB-ID TIME\nObjectType=0x7\nDataType=0x0007\n\
    AccessType=rw\nDefaultValue=0x00000100\nPDOMapping=0\n";

/// The checker's clean base EDS (CiA 301 communication objects, 6000h/6200h, no 1012h or 1016h).
pub(crate) fn base_eds() -> PathBuf {
    PathBuf::from(canopener_testkit::fixture::BASE_EDS)
}

/// An empty directory of its own for test `name`, removed when the test ends.
pub(crate) fn temp_dir(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("runtime-sim-{name}"))
}

/// base.eds with `extra` sections appended, written to `dir/name`.
pub(crate) fn base_eds_with(dir: &Path, name: &str, extra: &str) -> PathBuf {
    let mut text = std::fs::read_to_string(base_eds()).expect("base.eds");
    text.push_str(extra);
    let path = dir.join(name);
    canopener_testkit::fixture::write(&path, text).expect("test EDS");
    path
}

/// A frame written as candump does (`605#2318100101000000`).
pub(crate) fn frame(text: &str) -> CanFrame {
    canopener_can::candump::parse_compact_frame(text).expect("frame")
}
