//! The JSON form of a model: versioned, documented in `docs/eds-json.md`.
//!
//! ```json
//! {"format": "canopener-eds", "version": 1, "file_info": {...}, "device_info": {...}, "objects": {"1018": {...}}}
//! ```
//!
//! Values are the strings written in the file (so `0x191`, `$NODEID+0x180` and `1.5` survive unchanged);
//! generated objects and sub-objects carry an `origin` so writers leave them implied. A reader
//! refuses other formats and newer major versions instead of guessing.

use serde::{Deserialize, Serialize};

use crate::model::Eds;

/// The `format` member of every document.
pub const FORMAT: &str = "canopener-eds";
/// The version this build writes and the highest it reads.
pub const VERSION: u32 = 1;

#[derive(Serialize)]
struct EnvelopeOut<'a> {
    format: &'static str,
    version: u32,
    #[serde(flatten)]
    eds: &'a Eds,
}

#[derive(Deserialize)]
struct EnvelopeIn {
    format: String,
    version: u32,
}

/// Why a JSON document could not be read.
#[derive(Debug, thiserror::Error)]
pub enum JsonError {
    /// Not JSON, or not the shape of the model.
    #[error("line {line}, column {column}: {message}")]
    Syntax {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What serde_json said.
        message: String,
    },
    /// A JSON document of another kind.
    #[error("`format` is {found:?}, expected {FORMAT:?}: this is not a canopener EDS document")]
    WrongFormat {
        /// The format found.
        found: String,
    },
    /// Written by a newer canopener.
    #[error("version {found} is newer than the supported version {VERSION}; upgrade canopener")]
    UnsupportedVersion {
        /// The version found.
        found: u32,
    },
}

/// The model as pretty-printed JSON.
pub fn to_json(eds: &Eds) -> String {
    // Serialising plain structs, strings and maps with string keys cannot fail.
    serde_json::to_string_pretty(&EnvelopeOut {
        format: FORMAT,
        version: VERSION,
        eds,
    })
    .unwrap_or_default()
}

/// Reads a model from its JSON form.
pub fn from_json(text: &str) -> Result<Eds, JsonError> {
    let syntax = |e: serde_json::Error| JsonError::Syntax {
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    };
    // Check the envelope first, so a document of another kind gets that message, not a shape error.
    let envelope: EnvelopeIn = serde_json::from_str(text).map_err(syntax)?;
    if envelope.format != FORMAT {
        return Err(JsonError::WrongFormat {
            found: envelope.format,
        });
    }
    if envelope.version > VERSION {
        return Err(JsonError::UnsupportedVersion {
            found: envelope.version,
        });
    }
    serde_json::from_str(text).map_err(syntax)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load;

    #[test]
    fn round_trip_and_envelope_checks() {
        let text = "[FileInfo]\nFileName=a.eds\n[1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\n\
                    DefaultValue=$NODEID+0x180\n[1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n";
        let eds = load(text.as_bytes()).eds;
        let json = to_json(&eds);
        assert!(json.contains("\"format\": \"canopener-eds\""), "{json}");
        assert!(json.contains("\"DefaultValue\": \"$NODEID+0x180\""), "{json}");
        assert!(json.contains("\"1800\""), "{json}");
        assert_eq!(from_json(&json).unwrap(), eds);
        let wrong = json.replace("canopener-eds", "other");
        assert!(matches!(from_json(&wrong), Err(JsonError::WrongFormat { .. })));
        let newer = json.replace("\"version\": 1", "\"version\": 2");
        assert!(matches!(
            from_json(&newer),
            Err(JsonError::UnsupportedVersion { found: 2 })
        ));
        assert!(matches!(
            from_json("{\"format\":"),
            Err(JsonError::Syntax { line: 1, .. })
        ));
    }
}
