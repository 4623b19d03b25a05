//! Reading a topology file of either format: the format from the content, the model, the source
//! layer (for lossless writing) and what reading found.

use canopener_eds::syntax::Document;

use crate::codes::NetDiagnostic;
use crate::graphml::document::GraphMl;
use crate::model::{Format, Topology};

/// A topology file read.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The system.
    pub topology: Topology,
    /// What reading found, in the order found.
    pub diagnostics: Vec<NetDiagnostic>,
    /// The file as read, for writing it back in its own format without loss.
    pub source: Source,
}

/// The source layer of a file read.
#[derive(Debug, Clone)]
pub enum Source {
    /// A nodelist.cpj, every byte kept.
    Cpj(Document),
    /// A GraphML document, every element kept.
    Graphml(GraphMl),
}

impl Loaded {
    /// The format the file is in.
    pub fn format(&self) -> Format {
        match self.source {
            Source::Cpj(_) => Format::Cpj,
            Source::Graphml(_) => Format::Graphml,
        }
    }
}

/// The format of a file from its content: XML (anything whose first non-blank character is `<`) is
/// GraphML, anything else nodelist.cpj.
pub fn sniff(bytes: &[u8]) -> Format {
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if body.trim_ascii_start().starts_with(b"<") {
        Format::Graphml
    } else {
        Format::Cpj
    }
}

/// Reads a topology file. Never fails and never panics: what cannot be read is a diagnostic.
pub fn load(bytes: &[u8]) -> Loaded {
    match sniff(bytes) {
        Format::Cpj => {
            let (document, topology, diagnostics) = crate::cpj::read(bytes);
            Loaded {
                topology,
                diagnostics,
                source: Source::Cpj(document),
            }
        }
        Format::Graphml => {
            let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
            let text = String::from_utf8_lossy(body);
            let (document, mut diagnostics) = GraphMl::parse(&text);
            let topology = crate::graphml::read::topology(&document, &mut diagnostics);
            Loaded {
                topology,
                diagnostics,
                source: Source::Graphml(document),
            }
        }
    }
}
