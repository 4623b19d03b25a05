//! Writing a loaded description in another format: canonical EDS, a DCF for one node, CiA 311
//! XML, or canopener's JSON form.

use canopener_eds::dcf::{self, DcfError};
use canopener_eds::text::Unencodable;
use canopener_xdd::WriteOptions;

use crate::description::Description;

/// What to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Canonical CiA 306 EDS text; a DCF loses its DCF additions.
    Eds,
    /// A DCF for one node: the node-ID and bit rate given, or else those the description has.
    Dcf {
        /// The node-ID (1..=127).
        node_id: Option<u16>,
        /// The bit rate in kbit/s.
        bitrate: Option<u16>,
    },
    /// CiA 311 v1.1 as CANopenEditor writes it (an XDC when the description is a DCF).
    Xdd,
    /// canopener's JSON form, with a final newline.
    Json,
}

/// A description written in the target format.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Converted {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// For a DCF: the bit rate, when the description does not declare it supported
    /// (`BaudRate_<k>=1` missing). The DCF is written anyway; the caller should warn.
    pub undeclared_bitrate: Option<u16>,
    /// For an EDS made from a configuration: the DCF keys and sections it no longer carries
    /// ([`dcf::configuration_keys`]), for the caller to name; `--to dcf` keeps them.
    pub dropped: Vec<String>,
}

/// Why a description cannot be written as asked.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ConvertError {
    /// A DCF needs a node-ID and neither the caller nor the description gives one.
    #[error("a DCF needs a node-ID and the input has none")]
    NoNodeId,
    /// A DCF needs a bit rate and neither the caller nor the description gives one.
    #[error("a DCF needs a bit rate and the input has none")]
    NoBitrate,
    /// The node-ID or bit rate is not one a DCF can hold.
    #[error(transparent)]
    Dcf(#[from] DcfError),
    /// The text cannot be written in the file's own encoding.
    #[error(transparent)]
    Encoding(#[from] Unencodable),
}

/// Writes `description` in the `target` format.
pub fn convert(description: &Description, target: Target) -> Result<Converted, ConvertError> {
    let eds = &description.eds;
    let mut dropped = Vec::new();
    let (bytes, undeclared_bitrate) = match target {
        Target::Json => (
            format!("{}\n", canopener_eds::json::to_json(eds)).into_bytes(),
            None,
        ),
        Target::Xdd => (
            canopener_xdd::write(eds, &WriteOptions::CANOPEN_EDITOR).into_bytes(),
            None,
        ),
        Target::Eds if eds.is_dcf() => {
            dropped = dcf::configuration_keys(eds);
            (description.canonical_bytes(&dcf::to_eds(eds))?, None)
        }
        Target::Eds => (description.canonical_bytes(eds)?, None),
        // A configuration stays exactly what it is (issue 13: DCF -> XDC -> DCF added a ParameterValue to
        // every entry the DCF had left unset); only a template gets its values filled for one node.
        Target::Dcf { node_id, bitrate } if dcf::is_configuration(eds) => {
            let dcf = dcf::recommission(eds, node_id, bitrate)?;
            let undeclared = bitrate.filter(|b| !dcf::supports_bitrate(eds, *b));
            (description.canonical_bytes(&dcf)?, undeclared)
        }
        Target::Dcf { node_id, bitrate } => {
            let node = node_id
                .or_else(|| eds.node_id().map(u16::from))
                .ok_or(ConvertError::NoNodeId)?;
            let bitrate = bitrate
                .or_else(|| {
                    let configured = eds.commissioning.as_ref()?.baudrate.as_deref()?;
                    u16::try_from(canopener_eds::model::int_of(configured)?).ok()
                })
                .ok_or(ConvertError::NoBitrate)?;
            let dcf = dcf::to_dcf(eds, node, bitrate)?;
            let undeclared = (!dcf::supports_bitrate(eds, bitrate)).then_some(bitrate);
            (description.canonical_bytes(&dcf)?, undeclared)
        }
    };
    Ok(Converted {
        bytes,
        undeclared_bitrate,
        dropped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Format;

    const EDS: &[u8] = b"[FileInfo]\r\nFileName=io.eds\r\n[DeviceInfo]\r\nBaudRate_250=1\r\n\
        [1017]\r\nParameterName=Producer heartbeat time\r\nObjectType=0x7\r\nDataType=0x0006\r\n\
        AccessType=rw\r\nDefaultValue=0\r\nPDOMapping=0\r\n";

    fn load(bytes: &[u8]) -> Description {
        Description::load(Some("eds"), bytes).expect("EDS text always loads")
    }

    #[test]
    fn a_dcf_needs_a_node_and_a_bitrate_from_somewhere() {
        let eds = load(EDS);
        let dcf = |node_id, bitrate| convert(&eds, Target::Dcf { node_id, bitrate });
        assert_eq!(dcf(None, Some(250)), Err(ConvertError::NoNodeId));
        assert_eq!(dcf(Some(5), None), Err(ConvertError::NoBitrate));
        assert!(matches!(
            dcf(Some(0), Some(250)),
            Err(ConvertError::Dcf(DcfError::NodeId(0)))
        ));
        let made = dcf(Some(5), Some(250)).expect("a node and a declared bit rate");
        assert_eq!(made.undeclared_bitrate, None);
        let back = load(&made.bytes);
        assert_eq!((back.eds.node_id(), back.eds.is_dcf()), (Some(5), true));
        assert_eq!(
            dcf(Some(5), Some(500)).map(|c| c.undeclared_bitrate),
            Ok(Some(500))
        );
        let again = convert(
            &back,
            Target::Dcf {
                node_id: None,
                bitrate: None,
            },
        )
        .expect("the DCF's own");
        assert_eq!(load(&again.bytes).eds.node_id(), Some(5));
    }

    #[test]
    fn a_dcf_converted_to_eds_loses_its_configuration() {
        let dcf = convert(
            &load(EDS),
            Target::Dcf {
                node_id: Some(7),
                bitrate: Some(250),
            },
        )
        .expect("a DCF");
        let eds = convert(&load(&dcf.bytes), Target::Eds).expect("canonical EDS");
        let back = load(&eds.bytes);
        assert!(!back.eds.is_dcf() && back.eds.commissioning.is_none());
    }

    #[test]
    fn xdd_and_json_read_back_to_the_same_objects() {
        let eds = load(EDS);
        for (target, format) in [(Target::Xdd, Format::Xdd), (Target::Json, Format::Json)] {
            let written = convert(&eds, target).expect("always writable");
            let back = Description::load_as(format, &written.bytes).expect("canopener reads what it writes");
            assert!(
                canopener_eds::diff::diff_objects(&eds.eds, &back.eds).is_equivalent(),
                "{target:?}"
            );
        }
        let json = convert(&eds, Target::Json).expect("JSON");
        assert!(json.bytes.ends_with(b"}\n"));
    }
}
