//! PDO frames decoded into the values of their mapped objects (CiA 301 §7.2.2 PDO, the mapping
//! parameters 1600h–17FFh and 1A00h–1BFFh; reference §3.4–§3.6).
//!
//! Before changing this file read how CiA 301 packs a PDO: the mapped objects follow each other in
//! mapping order from bit 0 of byte 0 upwards, each one little-endian and exactly as many bits long
//! as its entry says, so fields need not start on a byte (a BOOLEAN takes one bit). Dummy entries
//! (data type indices 0001h–0007h, sub-index 0) take room but carry nothing.
//!
//! A [`PdoLayout`] comes from mapping entries ([`PdoLayout::new`]) or from a device's mapping
//! parameter ([`PdoLayout::from_od_values`], [`PdoLayout::from_od`]), optionally typed and named by
//! an EDS ([`PdoLayout::typed`]). Untyped fields decode as unsigned numbers of their width.

use std::fmt;

use canopener_od::{DataType, DynamicOd, ObjectKey, TypeKind};

use crate::pdo_config::{MappedObject, PdoConfigError, check_mapping};
use crate::value::{DisplayValue, le_u64, mask, sign_extend};

/// Where each mapped object sits in a PDO, and what it is if an EDS said so.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoLayout {
    fields: Vec<LayoutField>,
    bits: u32,
}

/// One mapping entry placed in the PDO.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LayoutField {
    /// The entry.
    pub mapped: MappedObject,
    /// The first bit of the field, counted from bit 0 of byte 0.
    pub offset: u32,
    /// The object's name, from [`PdoLayout::typed`].
    pub name: Option<String>,
    /// The object's data type, from [`PdoLayout::typed`].
    pub data_type: Option<DataType>,
}

/// The value of one mapped object in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedField {
    /// The object index.
    pub index: u16,
    /// The sub-index.
    pub sub: u8,
    /// The object's name, if the layout is typed.
    pub name: Option<String>,
    /// The object's data type, if the layout is typed.
    pub data_type: Option<DataType>,
    /// The first bit of the field in the frame.
    pub offset: u32,
    /// The field's length in bits.
    pub bits: u8,
    /// The field's bits as they were in the frame.
    pub raw: u64,
    /// The value, typed by `data_type`, or an unsigned number of `bits` bits without one.
    pub value: DisplayValue,
}

/// Why a layout could not be built or a frame not decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PdoDecodeError {
    /// A mapping no device would accept: too many entries or bits, a zero-length entry.
    #[error(transparent)]
    Mapping(#[from] PdoConfigError),
    /// A multiplexed PDO (mapping sub 0 = FEh or FFh), which has no fixed layout.
    #[error("mapping sub 0 is {count:#04X}: a multiplexed PDO (MPDO) has no fixed layout to decode")]
    Multiplexed {
        /// The value of sub 0.
        count: u8,
    },
    /// A mapping entry the count in sub 0 promises but the object does not have.
    #[error("mapping sub-index {sub:02X}h is missing, though sub 0 says there are {count} entries")]
    MissingEntry {
        /// The sub-index.
        sub: u8,
        /// The count in sub 0.
        count: u8,
    },
    /// A mapping parameter value of the wrong size.
    #[error(
        "mapping sub-index {sub:02X}h holds {len} byte(s); sub 0 is UNSIGNED8 and entries are UNSIGNED32"
    )]
    EntryLength {
        /// The sub-index.
        sub: u8,
        /// The number of bytes it holds.
        len: usize,
    },
    /// A frame shorter than the mapping.
    #[error(
        "the frame has {got} byte(s) but the mapping needs {needed} ({bits} bits); a device receiving it \
         as an RPDO would not process it (EMCY 8210h)"
    )]
    TooShort {
        /// The frame's length.
        got: usize,
        /// The bytes the mapping takes.
        needed: usize,
        /// The bits the mapping takes.
        bits: u32,
    },
}

impl PdoLayout {
    /// Places the entries one after the other from bit 0; refuses what no device would accept
    /// (more than 64 entries or bits, zero-length entries, dummies longer than their type).
    pub fn new(mapping: &[MappedObject]) -> Result<PdoLayout, PdoDecodeError> {
        let bits = check_mapping(mapping)?;
        let mut offset = 0;
        let fields = mapping
            .iter()
            .map(|mapped| {
                let field = LayoutField {
                    mapped: *mapped,
                    offset,
                    name: None,
                    data_type: None,
                };
                offset += u32::from(mapped.bits);
                field
            })
            .collect();
        Ok(PdoLayout { fields, bits })
    }

    /// Reads a device's mapping parameter (1600h.. or 1A00h..) through `read(sub)`, which returns the
    /// value of a sub-index as stored (sub 0 one byte, the entries four bytes little-endian) or
    /// `None` if it is missing. Sub 0 = 0 gives an empty layout.
    pub fn from_od_values(mut read: impl FnMut(u8) -> Option<Vec<u8>>) -> Result<PdoLayout, PdoDecodeError> {
        let count = match read(0).as_deref() {
            Some(&[count]) => count,
            Some(other) => {
                return Err(PdoDecodeError::EntryLength {
                    sub: 0,
                    len: other.len(),
                });
            }
            None => return Err(PdoDecodeError::MissingEntry { sub: 0, count: 0 }),
        };
        if count >= 0xFE {
            return Err(PdoDecodeError::Multiplexed { count });
        }
        if usize::from(count) > crate::pdo_config::MAX_MAPPED_OBJECTS {
            return Err(PdoConfigError::TooManyEntries {
                count: usize::from(count),
            }
            .into());
        }
        let mut mapping = Vec::with_capacity(usize::from(count));
        for sub in 1..=count {
            let value = read(sub).ok_or(PdoDecodeError::MissingEntry { sub, count })?;
            let entry: [u8; 4] = value
                .as_slice()
                .try_into()
                .map_err(|_| PdoDecodeError::EntryLength {
                    sub,
                    len: value.len(),
                })?;
            mapping.push(MappedObject::from_entry(u32::from_le_bytes(entry)));
        }
        PdoLayout::new(&mapping)
    }

    /// Reads the mapping parameter at `mapping_index` of an object dictionary, e.g. one built from
    /// an EDS or DCF, or a simulated device's.
    pub fn from_od(od: &DynamicOd, mapping_index: u16) -> Result<PdoLayout, PdoDecodeError> {
        PdoLayout::from_od_values(|sub| {
            od.get(ObjectKey::new(mapping_index, sub))
                .map(|entry| entry.value().to_vec())
        })
    }

    /// Names and types the fields by `lookup(index, sub)`, e.g. from an EDS; fields it returns
    /// `None` for stay untyped. Dummy entries are not looked up.
    pub fn typed(mut self, mut lookup: impl FnMut(u16, u8) -> Option<(String, DataType)>) -> PdoLayout {
        for field in &mut self.fields {
            if field.mapped.is_dummy() {
                continue;
            }
            if let Some((name, data_type)) = lookup(field.mapped.index, field.mapped.sub) {
                field.name = Some(name);
                field.data_type = Some(data_type);
            }
        }
        self
    }

    /// Every field in PDO order, dummies included.
    pub fn fields(&self) -> &[LayoutField] {
        &self.fields
    }

    /// The length of the mapping in bits.
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// The bytes a frame needs to carry the whole mapping.
    pub fn byte_len(&self) -> usize {
        self.bits.div_ceil(8) as usize
    }

    /// The values of the mapped objects in a frame's data, in mapping order, dummies left out.
    ///
    /// A frame shorter than the mapping is an error; bytes past the mapping are ignored (an RPDO
    /// receiver would process the frame and report EMCY 8220h). Partial mappings of a signed type
    /// are sign-extended from their width; a BOOLEAN is true when any of its bits is set; a REAL
    /// mapped with fewer bits than its type, or a string with a bit count that is not whole bytes,
    /// shows as an unsigned number.
    pub fn decode(&self, data: &[u8]) -> Result<Vec<DecodedField>, PdoDecodeError> {
        let needed = self.byte_len();
        let Some(mapped_bytes) = data.get(..needed) else {
            return Err(PdoDecodeError::TooShort {
                got: data.len(),
                needed,
                bits: self.bits,
            });
        };
        let frame = le_u64(mapped_bytes);
        let fields = self
            .fields
            .iter()
            .filter(|field| !field.mapped.is_dummy())
            .map(|field| {
                let bits = field.mapped.bits;
                let raw = frame.checked_shr(field.offset).unwrap_or(0) & mask(u32::from(bits));
                DecodedField {
                    index: field.mapped.index,
                    sub: field.mapped.sub,
                    name: field.name.clone(),
                    data_type: field.data_type,
                    offset: field.offset,
                    bits,
                    raw,
                    value: field_value(raw, bits, field.data_type),
                }
            })
            .collect();
        Ok(fields)
    }
}

/// Prints `6401:01 Analog input 1 = -1234 (0xFB2E)`, the name only if known.
impl fmt::Display for DecodedField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X}:{:02X}", self.index, self.sub)?;
        if let Some(name) = &self.name {
            write!(f, " {name}")?;
        }
        write!(f, " = {}", self.value)
    }
}

fn field_value(raw: u64, bits: u8, data_type: Option<DataType>) -> DisplayValue {
    let width = u32::from(bits);
    let bytes = || -> Vec<u8> {
        raw.to_le_bytes()
            .into_iter()
            .take(usize::from(bits / 8))
            .collect()
    };
    let whole_bytes = bits.is_multiple_of(8);
    match data_type.and_then(DataType::kind) {
        Some(TypeKind::Boolean) => DisplayValue::Bool(raw != 0),
        Some(TypeKind::Signed(_)) => DisplayValue::Signed {
            value: sign_extend(raw, width),
            bits: width,
        },
        Some(TypeKind::Real32) if bits == 32 => DisplayValue::Real32(f32::from_bits(raw as u32)),
        Some(TypeKind::Real64) if bits == 64 => DisplayValue::Real64(f64::from_bits(raw)),
        Some(TypeKind::VisibleString) if whole_bytes => DisplayValue::Text(bytes()),
        Some(TypeKind::OctetString | TypeKind::Domain) if whole_bytes => DisplayValue::Bytes(bytes()),
        _ => DisplayValue::Unsigned {
            value: raw,
            bits: width,
        },
    }
}

#[cfg(test)]
mod tests {
    use canopener_od::{Access, Entry};
    use proptest::prelude::*;

    use super::*;

    fn layout(mapping: &[(u16, u8, u8)]) -> PdoLayout {
        let mapping: Vec<MappedObject> = mapping
            .iter()
            .map(|&(i, s, b)| MappedObject::new(i, s, b))
            .collect();
        PdoLayout::new(&mapping).expect("valid mapping")
    }

    /// The CiA 401 names and types the tests look objects up by.
    fn cia401(index: u16, sub: u8) -> Option<(String, DataType)> {
        match (index, sub) {
            (0x6000, _) => Some((format!("Read input {sub}"), DataType::UNSIGNED8)),
            (0x6020, _) => Some((format!("Read input bit {sub}"), DataType::BOOLEAN)),
            (0x6401, _) => Some((format!("Analog input {sub}"), DataType::INTEGER16)),
            (0x2000, 1) => Some(("Label".to_owned(), DataType::VISIBLE_STRING)),
            (0x2000, 2) => Some(("Blob".to_owned(), DataType::OCTET_STRING)),
            (0x2000, 3) => Some(("Ratio".to_owned(), DataType::REAL32)),
            (0x2000, 4) => Some(("Total".to_owned(), DataType::REAL64)),
            _ => None,
        }
    }

    /// The decoded frame as lines `offset+bits index:sub name = value`.
    fn check(layout: &PdoLayout, data: &[u8]) -> Vec<String> {
        match layout.decode(data) {
            Ok(fields) => fields
                .iter()
                .map(|f| format!("@{}+{} {f}", f.offset, f.bits))
                .collect(),
            Err(err) => vec![format!("error: {err}")],
        }
    }

    #[test]
    fn one_seven_and_sixteen_bits_around_a_dummy() {
        let layout = layout(&[(0x6020, 1, 1), (0x6000, 2, 7), (0x0005, 0, 8), (0x6401, 1, 16)]).typed(cia401);
        assert_eq!((layout.bits(), layout.byte_len()), (32, 4));
        // Bit 0: 1; bits 1..7: 55h; byte 1: the dummy; bytes 2..3: -1234.
        let data = [0x55 << 1 | 1, 0xEE, 0x2E, 0xFB];
        assert_eq!(
            check(&layout, &data),
            [
                "@0+1 6020:01 Read input bit 1 = true",
                "@1+7 6000:02 Read input 2 = 85 (0x55)",
                "@16+16 6401:01 Analog input 1 = -1234 (0xFB2E)",
            ]
        );
        // Untyped, the same frame is raw numbers.
        let untyped = PdoLayout::new(&layout.fields().iter().map(|f| f.mapped).collect::<Vec<_>>()).unwrap();
        assert_eq!(
            check(&untyped, &data),
            [
                "@0+1 6020:01 = 1 (0x1)",
                "@1+7 6000:02 = 85 (0x55)",
                "@16+16 6401:01 = 64302 (0xFB2E)",
            ]
        );
    }

    #[test]
    fn fields_across_byte_boundaries() {
        let layout =
            layout(&[(0x6000, 1, 3), (0x2100, 1, 16), (0x6401, 2, 12), (0x6000, 3, 5)]).typed(cia401);
        // 3 bits 101b, 16 bits ABCDh, 12 bits signed -2 (FFEh), 5 bits 10011b.
        let packed: u64 = 0b101 | 0xABCD << 3 | 0xFFE << 19 | 0b10011 << 31;
        let data = packed.to_le_bytes();
        assert_eq!(
            check(&layout, &data[..5]),
            [
                "@0+3 6000:01 Read input 1 = 5 (0x5)",
                "@3+16 2100:01 = 43981 (0xABCD)",
                "@19+12 6401:02 Analog input 2 = -2 (0xFFE)",
                "@31+5 6000:03 Read input 3 = 19 (0x13)",
            ]
        );
    }

    #[test]
    fn sixty_four_bit_fields_and_typed_bytes() {
        let total = layout(&[(0x2000, 4, 64)]).typed(cia401);
        assert_eq!(
            check(&total, &(-2.5f64).to_le_bytes()),
            ["@0+64 2000:04 Total = -2.5"]
        );
        let raw = layout(&[(0x2200, 1, 64)]);
        assert_eq!(
            check(&raw, &[0xFF; 8]),
            ["@0+64 2200:01 = 18446744073709551615 (0xFFFFFFFFFFFFFFFF)"]
        );
        let mixed = layout(&[(0x2000, 1, 24), (0x2000, 2, 8), (0x2000, 3, 32)]).typed(cia401);
        let mut data = b"ab\x07\xFF".to_vec();
        data.extend_from_slice(&0.5f32.to_le_bytes());
        assert_eq!(
            check(&mixed, &data),
            [
                r#"@0+24 2000:01 Label = "ab\x07""#,
                "@24+8 2000:02 Blob = FF",
                "@32+32 2000:03 Ratio = 0.5",
            ]
        );
        // A REAL32 mapped with 16 bits has no float value: shown raw.
        let partial = layout(&[(0x2000, 3, 16), (0x2000, 1, 4)]).typed(cia401);
        assert_eq!(
            check(&partial, &[0x34, 0x12, 0x0A]),
            [
                "@0+16 2000:03 Ratio = 4660 (0x1234)",
                "@16+4 2000:01 Label = 10 (0xA)"
            ]
        );
    }

    #[test]
    fn short_frames_are_errors_and_long_ones_are_fine() {
        let layout = layout(&[(0x6000, 1, 8), (0x6401, 1, 16), (0x0001, 0, 1)]);
        assert_eq!(layout.byte_len(), 4);
        assert_eq!(
            layout.decode(&[1, 2, 3]),
            Err(PdoDecodeError::TooShort {
                got: 3,
                needed: 4,
                bits: 25
            })
        );
        assert_eq!(
            check(&layout, &[]),
            [
                "error: the frame has 0 byte(s) but the mapping needs 4 (25 bits); a device receiving it as an \
              RPDO would not process it (EMCY 8210h)"
            ]
        );
        assert_eq!(
            check(&layout, &[1, 2, 3, 0x80, 9, 9, 9, 9]),
            ["@0+8 6000:01 = 1 (0x01)", "@8+16 6401:01 = 770 (0x0302)"]
        );
        let empty = PdoLayout::new(&[]).unwrap();
        assert_eq!(empty.decode(&[]), Ok(Vec::new()));
    }

    #[test]
    fn mappings_no_device_accepts_are_refused() {
        let too_long: Vec<MappedObject> = (0..9).map(|sub| MappedObject::new(0x6000, sub, 8)).collect();
        assert_eq!(
            PdoLayout::new(&too_long),
            Err(PdoDecodeError::Mapping(PdoConfigError::TooManyBits { bits: 72 }))
        );
        assert_eq!(
            PdoLayout::new(&[MappedObject::new(0x6000, 1, 0)])
                .unwrap_err()
                .to_string(),
            "mapping entry 6000:01:0 has length 0: give 1 to 64 bits, e.g. 6000:01:8"
        );
    }

    fn values(sub0: Option<&[u8]>, entries: &[u32]) -> impl FnMut(u8) -> Option<Vec<u8>> {
        let sub0 = sub0.map(<[u8]>::to_vec);
        let entries = entries.to_vec();
        move |sub| match sub {
            0 => sub0.clone(),
            _ => entries
                .get(usize::from(sub) - 1)
                .map(|e| e.to_le_bytes().to_vec()),
        }
    }

    #[test]
    fn layout_from_mapping_parameter_values() {
        let layout =
            PdoLayout::from_od_values(values(Some(&[2]), &[0x6000_0108, 0x6401_0110, 0x1234_5678])).unwrap();
        assert_eq!(
            layout
                .fields()
                .iter()
                .map(|f| (f.mapped.entry(), f.offset))
                .collect::<Vec<_>>(),
            [(0x6000_0108, 0), (0x6401_0110, 8)]
        );
        assert_eq!(
            PdoLayout::from_od_values(values(Some(&[0]), &[])).map(|l| l.bits()),
            Ok(0)
        );
        assert_eq!(
            PdoLayout::from_od_values(values(Some(&[3]), &[0x6000_0108, 0x6000_0208])),
            Err(PdoDecodeError::MissingEntry { sub: 3, count: 3 })
        );
        assert_eq!(
            PdoLayout::from_od_values(values(Some(&[0xFE]), &[])),
            Err(PdoDecodeError::Multiplexed { count: 0xFE })
        );
        assert_eq!(
            PdoLayout::from_od_values(values(Some(&[0x41]), &[])),
            Err(PdoDecodeError::Mapping(PdoConfigError::TooManyEntries {
                count: 0x41
            }))
        );
        assert_eq!(
            PdoLayout::from_od_values(values(Some(&[1, 0]), &[])),
            Err(PdoDecodeError::EntryLength { sub: 0, len: 2 })
        );
        assert_eq!(
            PdoLayout::from_od_values(values(None, &[])),
            Err(PdoDecodeError::MissingEntry { sub: 0, count: 0 })
        );
        let short_entry = |sub: u8| {
            if sub == 0 {
                Some(vec![1])
            } else {
                Some(vec![8, 1, 0])
            }
        };
        assert_eq!(
            PdoLayout::from_od_values(short_entry).unwrap_err().to_string(),
            "mapping sub-index 01h holds 3 byte(s); sub 0 is UNSIGNED8 and entries are UNSIGNED32"
        );
        assert_eq!(
            PdoLayout::from_od_values(values(Some(&[2]), &[0x6401_0120, 0x6401_0221, 0])),
            Err(PdoDecodeError::Mapping(PdoConfigError::TooManyBits { bits: 65 }))
        );
    }

    #[test]
    fn layout_from_an_object_dictionary() {
        let mut od = DynamicOd::with_capacity(8);
        let entry = |sub, data_type, value: &[u8]| {
            Entry::new(ObjectKey::new(0x1A00, sub), data_type, Access::Rw, value).expect("entry")
        };
        od.insert(entry(0, DataType::UNSIGNED8, &[2])).unwrap();
        od.insert(entry(1, DataType::UNSIGNED32, &0x6000_0108u32.to_le_bytes()))
            .unwrap();
        od.insert(entry(2, DataType::UNSIGNED32, &0x0006_0010u32.to_le_bytes()))
            .unwrap();
        let layout = PdoLayout::from_od(&od, 0x1A00).unwrap().typed(cia401);
        assert_eq!(
            check(&layout, &[7, 0, 0]),
            ["@0+8 6000:01 Read input 1 = 7 (0x07)"]
        );
        assert_eq!(
            PdoLayout::from_od(&od, 0x1A01),
            Err(PdoDecodeError::MissingEntry { sub: 0, count: 0 })
        );
    }

    /// Packs values into a PDO the way CiA 301 lays them out, independently of `decode`.
    fn pack(fields: &[(u8, u64)]) -> Vec<u8> {
        let mut bits_out = Vec::new();
        for &(bits, value) in fields {
            for bit_idx in 0..bits {
                bits_out.push(value >> bit_idx & 1 == 1);
            }
        }
        let mut data = vec![0u8; bits_out.len().div_ceil(8)];
        for (bit_idx, bit) in bits_out.iter().enumerate() {
            if *bit {
                data[bit_idx / 8] |= 1 << (bit_idx % 8);
            }
        }
        data
    }

    fn widths_and_values() -> impl Strategy<Value = Vec<(u8, u64)>> {
        prop::collection::vec((1u8..=64, any::<u64>()), 0..12).prop_map(|fields| {
            let mut total = 0u32;
            fields
                .into_iter()
                .take_while(|(bits, _)| {
                    total += u32::from(*bits);
                    total <= 64
                })
                .map(|(bits, value)| (bits, value & mask(u32::from(bits))))
                .collect()
        })
    }

    proptest! {
        #[test]
        fn decodes_what_cia_301_packing_produced(fields in widths_and_values()) {
            let mapping: Vec<MappedObject> = fields
                .iter()
                .zip(1u8..)
                .map(|(&(bits, _), sub)| MappedObject::new(0x2000, sub, bits))
                .collect();
            let layout = PdoLayout::new(&mapping).unwrap();
            let data = pack(&fields);
            prop_assert_eq!(data.len(), layout.byte_len());
            let decoded = layout.decode(&data).unwrap();
            let raws: Vec<(u8, u64)> = decoded.iter().map(|f| (f.bits, f.raw)).collect();
            prop_assert_eq!(raws, fields.clone());
            for field in &decoded {
                prop_assert_eq!(field.value.as_u64(), Some(field.raw));
            }
            if !data.is_empty() {
                let short = layout.decode(&data[..data.len() - 1]);
                prop_assert!(
                    matches!(short, Err(PdoDecodeError::TooShort { .. })),
                    "expected TooShort, got {:?}",
                    short
                );
            }
        }

        #[test]
        fn any_frame_against_any_mapping_never_panics(
            entries in prop::collection::vec(any::<u32>(), 0..10),
            data in prop::collection::vec(any::<u8>(), 0..9),
        ) {
            let count = entries.len() as u8;
            let read = |sub: u8| match sub {
                0 => Some(vec![count]),
                _ => entries.get(usize::from(sub) - 1).map(|e| e.to_le_bytes().to_vec()),
            };
            if let Ok(layout) = PdoLayout::from_od_values(read) {
                let layout = layout.typed(cia401);
                match layout.decode(&data) {
                    Ok(fields) => prop_assert!(fields.len() <= entries.len()),
                    Err(err) => prop_assert!(matches!(err, PdoDecodeError::TooShort { .. }), "{}", err),
                }
            }
        }
    }
}
