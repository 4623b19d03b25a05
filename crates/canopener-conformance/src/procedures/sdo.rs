//! SDO requests as the analyses name them, and the verdicts on a confirmation or refusal CiA 301
//! requires.

use crate::context::{Reply, hex};
use crate::finding::{Evidence, Finding};
use crate::requirements::{Accepted, code_meaning};

/// The verdict on a request that CiA 301 requires the device to refuse with one of `accepted`.
pub fn expect_refusal(
    request: &str,
    reply: &Reply,
    accepted: Accepted,
    clause: &str,
    cause: &str,
) -> Finding {
    match reply {
        Reply::Refused(code) if accepted.accepts(*code) => {
            Finding::pass(format!("refused with {}", code_meaning(*code)))
        }
        other => Finding::fail(
            format!(
                "{request}: expected abort {}, got {}",
                accepted.list(),
                other.describe()
            ),
            Evidence {
                request: request.to_owned(),
                requirement: format!(
                    "{clause}: the server aborts with {} ({})",
                    accepted.list(),
                    accepted.source
                ),
                answer: other.describe(),
                cause: cause.to_owned(),
            },
        ),
    }
}

/// The failure of a request CiA 301 requires the device to carry out.
pub fn refused_unexpectedly(request: &str, reply: &Reply, clause: &str, cause: &str) -> Finding {
    Finding::fail(
        format!("{request}: {}", reply.describe()),
        Evidence {
            request: request.to_owned(),
            requirement: format!("{clause}: the server confirms the transfer"),
            answer: reply.describe(),
            cause: cause.to_owned(),
        },
    )
}

/// `SDO upload 1000h:00`.
pub fn upload_text(entry: (u16, u8)) -> String {
    format!("SDO upload {:04X}h:{:02X}", entry.0, entry.1)
}

/// `SDO download 1017h:00 = 64 00`.
pub fn download_text(entry: (u16, u8), data: &[u8]) -> String {
    format!("SDO download {:04X}h:{:02X} = {}", entry.0, entry.1, hex(data))
}

/// A 4-byte value read as UNSIGNED32.
pub fn u32_of(reply: &Reply) -> Option<u32> {
    match reply {
        Reply::Done(d) if d.len() == 4 => Some(u32::from_le_bytes([d[0], d[1], d[2], d[3]])),
        _ => None,
    }
}
