//! The device's EMCY producer, for the tests that provoke an error and look for its EMCY.

use crate::context::{Ctx, Reply};
use crate::finding::{Finding, Prepared};
use crate::procedures::sdo::{read_described, refused_unexpectedly, u32_of, upload_text};
use crate::requirements as req;

/// The CAN-ID the device sends EMCY on (1014h, CiA 301 §7.2.7). Not applicable when the EDS has no
/// 1014h or 1014h has bit 31 set (the EMCY is not valid: CiA 301 lets a device run without one); a
/// failure when the device does not serve the 1014h its EDS describes.
pub fn emcy_producer(ctx: &mut Ctx<'_, '_>) -> Prepared<u16> {
    if !ctx.model().entry(0x1014, 0).is_some_and(|e| e.readable()) {
        return Ok(Err(Finding::not_applicable(
            "the EDS has no readable 1014h (COB-ID EMCY): no EMCY producer",
        )));
    }
    let value = match read_described(ctx, 0x1014, 0, "the COB-ID EMCY")? {
        Ok(value) => value,
        Err(failed) => return Ok(Err(failed)),
    };
    Ok(match u32_of(&Reply::Done(value.clone())) {
        Some(cob) if cob & 0x8000_0000 != 0 => Err(Finding::not_applicable(format!(
            "1014h = {cob:#010X} has bit 31 set: the EMCY producer is not valid"
        ))),
        Some(cob) => Ok((cob & 0x7FF) as u16),
        None => Err(refused_unexpectedly(
            &upload_text((0x1014, 0)),
            &Reply::Done(value),
            req::EMCY,
            "1014h does not read as 4 bytes",
        )),
    })
}
