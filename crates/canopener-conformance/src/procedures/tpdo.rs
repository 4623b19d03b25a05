//! Setting a TPDO up for a test the way CiA 301 §7.5.2.37 allows: disabled, changed, enabled again.

use crate::context::{Ctx, Reply};
use crate::device_model::{PdoDirection, PdoModel};
use crate::finding::Stop;
use crate::procedures::sdo::{download_text, u32_of};

/// The first TPDO whose communication parameter sub-indices `subs` the EDS makes writable, with a
/// CAN-ID and at least one mapped object (a mapping of 0 entries disables a PDO, CiA 301
/// §7.5.2.38), and its current COB-ID.
pub fn configurable_tpdo(ctx: &mut Ctx<'_, '_>, subs: &[u8]) -> Result<Option<(PdoModel, u32)>, Stop> {
    for pdo in ctx.model().pdos(PdoDirection::Transmit) {
        if let Some(found) = configurable_tpdo_at(ctx, &pdo, subs)? {
            return Ok(Some(found));
        }
    }
    Ok(None)
}

/// `pdo` with its current COB-ID if the EDS makes `subs` of its communication parameter writable,
/// it maps data and has a CAN-ID.
pub fn configurable_tpdo_at(
    ctx: &mut Ctx<'_, '_>,
    pdo: &PdoModel,
    subs: &[u8],
) -> Result<Option<(PdoModel, u32)>, Stop> {
    if !subs
        .iter()
        .all(|sub| ctx.model().entry(pdo.comm, *sub).is_some_and(|e| e.writable()))
    {
        return Ok(None);
    }
    let Some(cob) = u32_of(&ctx.read(pdo.comm, 1)?) else {
        return Ok(None);
    };
    let Some(mapping) = pdo.mapping else {
        return Ok(None);
    };
    let mapped = matches!(ctx.read(mapping, 0)?, Reply::Done(d) if d.first().is_some_and(|n| *n > 0));
    Ok((mapped && cob & 0x7FF != 0).then(|| (pdo.clone(), cob)))
}

/// Configures a TPDO the way CiA 301 §7.5.2.37 allows: disabled, `settings` written (sub-index,
/// value), enabled again with its CAN-ID (and RTR allowed when `rtr`). Every value is written back
/// after the test. Returns the refusal that stopped it, if any.
pub fn configure_tpdo(
    ctx: &mut Ctx<'_, '_>,
    pdo: &PdoModel,
    cob: u32,
    settings: &[(u8, Vec<u8>)],
    rtr: bool,
) -> Result<Option<String>, Stop> {
    let enabled = if rtr { cob & 0x3FFF_FFFF } else { cob & 0x7FFF_FFFF };
    let mut steps = vec![(1u8, (cob | 0x8000_0000).to_le_bytes().to_vec())];
    steps.extend(settings.iter().cloned());
    steps.push((1, enabled.to_le_bytes().to_vec()));
    for (sub, data) in steps {
        let reply = ctx.modify(pdo.comm, sub, data.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(Some(format!(
                "{} got {}",
                download_text((pdo.comm, sub), &data),
                reply.describe()
            )));
        }
    }
    Ok(None)
}
