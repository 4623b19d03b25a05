//! SDO requests as the analyses name them, and the verdicts on a confirmation or refusal CiA 301
//! requires.

use crate::context::{Ctx, Reply, hex};
use crate::finding::{Evidence, Finding, Prepared};
use crate::requirements::{self as req, Accepted, code_meaning};

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
                cause: cause_of(other, cause),
            },
        ),
    }
}

/// The cause a failure names: `cause` for a wrong answer to the request itself, the protocol
/// error for one that broke it (then the request's own outcome is unknown).
fn cause_of(reply: &Reply, cause: &str) -> String {
    match reply {
        Reply::Broken { .. } => {
            "the SDO server broke the SDO protocol (CiA 301 §7.2.4.3), so what it does with the request itself is unknown"
                .to_owned()
        }
        _ => cause.to_owned(),
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
            cause: cause_of(reply, cause),
        },
    )
}

/// Reads `index`:`sub`, an entry the EDS describes as readable, whose value (`what`) a test needs
/// before it can measure anything: any answer but the value ends the test with a failure, since
/// CiA 301 requires the server to serve what the device describes (a timeout is a failure, never "the
/// feature is absent").
pub fn read_described(ctx: &mut Ctx<'_, '_>, index: u16, sub: u8, what: &str) -> Prepared<Vec<u8>> {
    Ok(match ctx.read(index, sub)? {
        Reply::Done(value) => Ok(value),
        other => Err(refused_unexpectedly(
            &upload_text((index, sub)),
            &other,
            req::SDO_UPLOAD,
            &format!("the device does not serve {what}, which its EDS describes as readable"),
        )),
    })
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
        Reply::Done(d) if let Ok(bytes) = <[u8; 4]>::try_from(d.as_slice()) => {
            Some(u32::from_le_bytes(bytes))
        }
        _ => None,
    }
}
