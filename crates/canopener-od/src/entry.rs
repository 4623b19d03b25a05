//! One object dictionary entry: a value of a data type at a key, with its access rules.
//!
//! The access checks are those an SDO server makes (CiA 301 §7.2.4.3.17 names the abort code for
//! each failure); the attributes are the keys of a CiA 306-1 §4.6.3.2 object description.

use std::fmt;
use std::ops::Deref;

use crate::access::Access;
use crate::data_type::DataType;
use crate::error::OdError;
use crate::key::ObjectKey;
use crate::number::Number;
use crate::obj_flags::ObjFlags;
use crate::value::ValueBytes;

/// An entry of the object dictionary.
///
/// The value is kept as the little-endian bytes CiA 301 defines for its data type, so an SDO or PDO
/// copies it without conversion. Values of up to 22 bytes are stored inline, without an allocation.
///
/// Every `Entry` is consistent: the value has the length its type demands, limits exist only on
/// numeric types and are encoded like the value, and a maximum length only on variable-length
/// types. Once an entry is in a [`DynamicOd`](crate::DynamicOd) its key and data type are fixed;
/// the dictionary hands out [`EntryMut`] to change the rest.
///
/// Limits are stored as little-endian bytes of the entry's own type rather than as, say, `i128`:
/// one encoding then serves value and limits, a limit can never lie outside what the type can
/// represent (a limit of 300 on an UNSIGNED8 cannot be built), REAL limits fit too, and the check
/// on a write decodes both sides with the same [`Number::decode`]. Limits restrict what the
/// network writes (CiA 301 gives their abort codes for downloads only); the device's own
/// [`EntryMut::set_value`] is not bound by them, and neither is the initial value, because real
/// EDS files have defaults outside their limits and a simulator must reproduce such devices.
#[derive(Clone, PartialEq)]
pub struct Entry {
    key: ObjectKey,
    data_type: DataType,
    access: Access,
    pdo_mapping: bool,
    obj_flags: ObjFlags,
    value: ValueBytes,
    // Limits in the entry's own encoding, padded with zeros to the widest numeric type.
    low_limit: Option<[u8; 8]>,
    high_limit: Option<[u8; 8]>,
    max_len: Option<u32>,
}

/// Why an entry cannot be built as described.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EntryError {
    /// The value's length does not match a fixed-size data type.
    #[error(
        "the value of {key} has {len} bytes but {data_type} takes {expected}; \
         give it as exactly {expected} little-endian bytes"
    )]
    ValueLength {
        /// The entry being built.
        key: ObjectKey,
        /// Its data type.
        data_type: DataType,
        /// The number of bytes the type takes.
        expected: usize,
        /// The number of bytes given.
        len: usize,
    },
    /// A UNICODE_STRING value with an odd number of bytes.
    #[error(
        "the value of {key} has {len} bytes, which is not a whole number of UNICODE_STRING code units; \
         give an even number of bytes"
    )]
    UnicodeOddLength {
        /// The entry being built.
        key: ObjectKey,
        /// The number of bytes given.
        len: usize,
    },
    /// Limits given for a type that is not an integer or REAL type.
    #[error(
        "{key} of type {data_type} cannot have limits; LowLimit and HighLimit apply to integer and REAL types only"
    )]
    LimitOnNonNumeric {
        /// The entry being built.
        key: ObjectKey,
        /// Its data type.
        data_type: DataType,
    },
    /// A limit whose length does not match the data type.
    #[error(
        "a limit of {key} has {len} bytes but {data_type} takes {expected}; \
         give limits in the same little-endian encoding as the value"
    )]
    LimitLength {
        /// The entry being built.
        key: ObjectKey,
        /// Its data type.
        data_type: DataType,
        /// The number of bytes the type takes.
        expected: usize,
        /// The number of bytes given.
        len: usize,
    },
    /// A REAL limit that is not a number.
    #[error("a limit of {key} is not a number; give a number or leave the limit out")]
    LimitIsNan {
        /// The entry being built.
        key: ObjectKey,
    },
    /// The low limit is above the high limit (an SDO server would abort with 0609 0036h).
    #[error("the low limit {low} of {key} is above its high limit {high}; swap them or correct one")]
    LimitsInverted {
        /// The entry being built.
        key: ObjectKey,
        /// The low limit given.
        low: Number,
        /// The high limit given.
        high: Number,
    },
    /// A maximum length given for a fixed-size type.
    #[error(
        "{key} of type {data_type} has a fixed size; a maximum length applies to \
         VISIBLE_STRING, OCTET_STRING, UNICODE_STRING and DOMAIN only"
    )]
    MaxLenOnFixedSize {
        /// The entry being built.
        key: ObjectKey,
        /// Its data type.
        data_type: DataType,
    },
    /// A maximum length shorter than the value the entry already holds.
    #[error(
        "the maximum length {max_len} of {key} is shorter than its value of {len} bytes; raise the maximum or shorten the value"
    )]
    MaxLenBelowValue {
        /// The entry being built.
        key: ObjectKey,
        /// The maximum length given.
        max_len: u32,
        /// The length of the value.
        len: usize,
    },
}

/// A mutable handle to an entry inside a [`DynamicOd`](crate::DynamicOd).
///
/// It changes the value, access type and flags in place but never the key or the data type, which
/// keeps the dictionary sorted and every value consistent with its type. Reading goes through
/// `Deref<Target = Entry>`.
#[derive(Debug)]
pub struct EntryMut<'a> {
    entry: &'a mut Entry,
}

impl Entry {
    /// An entry of `data_type` holding `value` (little-endian bytes), not PDO-mappable, without
    /// limits or flags.
    ///
    /// Fixed-size types need exactly their size in bytes; VISIBLE_STRING, OCTET_STRING and DOMAIN
    /// take any length and UNICODE_STRING any even length. Data types that are not CiA 301 basic
    /// types are opaque: the first value fixes their length.
    pub fn new(
        key: ObjectKey,
        data_type: DataType,
        access: Access,
        value: &[u8],
    ) -> Result<Entry, EntryError> {
        if let Some(expected) = data_type.byte_size()
            && value.len() != expected
        {
            return Err(EntryError::ValueLength {
                key,
                data_type,
                expected,
                len: value.len(),
            });
        }
        if data_type == DataType::UNICODE_STRING && !value.len().is_multiple_of(2) {
            return Err(EntryError::UnicodeOddLength {
                key,
                len: value.len(),
            });
        }
        Ok(Entry {
            key,
            data_type,
            access,
            pdo_mapping: false,
            obj_flags: ObjFlags::NONE,
            value: ValueBytes::new(value),
            low_limit: None,
            high_limit: None,
            max_len: None,
        })
    }

    /// The entry with its `PDOMapping` attribute set to `pdo_mapping`.
    pub fn with_pdo_mapping(mut self, pdo_mapping: bool) -> Entry {
        self.pdo_mapping = pdo_mapping;
        self
    }

    /// The entry with its `ObjFlags` set to `obj_flags`.
    pub fn with_obj_flags(mut self, obj_flags: ObjFlags) -> Entry {
        self.obj_flags = obj_flags;
        self
    }

    /// The entry with a `LowLimit` and `HighLimit`, each `None` for no limit and otherwise encoded
    /// like the value.
    ///
    /// Fails for types other than integers and REALs, for limits of the wrong length, for a NaN
    /// limit, and when the low limit is above the high limit.
    pub fn with_limits(mut self, low: Option<&[u8]>, high: Option<&[u8]>) -> Result<Entry, EntryError> {
        let low = low.map(|bytes| self.limit_bytes(bytes)).transpose()?;
        let high = high.map(|bytes| self.limit_bytes(bytes)).transpose()?;
        self.low_limit = low;
        self.high_limit = high;
        if let (Some(low), Some(high)) = (self.low_limit(), self.high_limit())
            && low > high
        {
            return Err(EntryError::LimitsInverted {
                key: self.key,
                low,
                high,
            });
        }
        Ok(self)
    }

    /// The entry with a maximum length in bytes for later writes; only for variable-length types,
    /// which are otherwise unbounded.
    ///
    /// A device with a fixed string buffer is modelled this way: a longer SDO write is refused
    /// with [`OdError::LengthTooHigh`]. The length is a `u32` because an SDO transfer announces its size as UNSIGNED32.
    pub fn with_max_len(mut self, max_len: u32) -> Result<Entry, EntryError> {
        if !self.data_type.is_variable_length() {
            return Err(EntryError::MaxLenOnFixedSize {
                key: self.key,
                data_type: self.data_type,
            });
        }
        if usize_from(max_len) < self.value.len() {
            return Err(EntryError::MaxLenBelowValue {
                key: self.key,
                max_len,
                len: self.value.len(),
            });
        }
        self.max_len = Some(max_len);
        Ok(self)
    }

    /// The entry's index and sub-index.
    pub fn key(&self) -> ObjectKey {
        self.key
    }

    /// The entry's data type.
    pub fn data_type(&self) -> DataType {
        self.data_type
    }

    /// The entry's access type.
    pub fn access(&self) -> Access {
        self.access
    }

    /// The `PDOMapping` attribute: whether the entry may be mapped into a PDO at all.
    pub fn pdo_mapping(&self) -> bool {
        self.pdo_mapping
    }

    /// Whether the entry may be mapped into a transmit PDO: `PDOMapping` is set and the access
    /// type allows the direction.
    pub fn tpdo_mappable(&self) -> bool {
        self.pdo_mapping && self.access.tpdo_mappable()
    }

    /// Whether the entry may be mapped into a receive PDO: `PDOMapping` is set and the access type
    /// allows the direction.
    pub fn rpdo_mappable(&self) -> bool {
        self.pdo_mapping && self.access.rpdo_mappable()
    }

    /// The entry's `ObjFlags`.
    pub fn obj_flags(&self) -> ObjFlags {
        self.obj_flags
    }

    /// The value's little-endian bytes, regardless of the access type (what the device itself and
    /// a TPDO see).
    pub fn value(&self) -> &[u8] {
        self.value.as_slice()
    }

    /// The value as a number, for integer and REAL entries.
    pub fn number(&self) -> Option<Number> {
        Number::decode(self.data_type, self.value())
    }

    /// The `LowLimit`, if the entry has one.
    pub fn low_limit(&self) -> Option<Number> {
        self.low_limit.and_then(|limit| self.decode_limit(limit))
    }

    /// The `HighLimit`, if the entry has one.
    pub fn high_limit(&self) -> Option<Number> {
        self.high_limit.and_then(|limit| self.decode_limit(limit))
    }

    /// The most bytes a write may store, for variable-length entries built with
    /// [`with_max_len`](Entry::with_max_len).
    pub fn max_len(&self) -> Option<u32> {
        self.max_len
    }

    /// The value as an SDO upload reads it: refused with [`OdError::WriteOnly`] for `wo` entries.
    pub fn read(&self) -> Result<&[u8], OdError> {
        if !self.access.readable() {
            return Err(OdError::WriteOnly { key: self.key });
        }
        Ok(self.value())
    }

    /// Stores `data` as an SDO download does: the access type must allow writing, the length must
    /// suit the type and a number must lie within the limits. Nothing changes on error.
    fn write(&mut self, data: &[u8]) -> Result<(), OdError> {
        if !self.access.writable() {
            return Err(OdError::ReadOnly {
                key: self.key,
                access: self.access,
            });
        }
        self.check_length(data.len())?;
        self.check_limits(data)?;
        self.value.set(data);
        Ok(())
    }

    /// Stores `data` as the device's application does: only the length is checked.
    fn set_value(&mut self, data: &[u8]) -> Result<(), OdError> {
        self.check_length(data.len())?;
        self.value.set(data);
        Ok(())
    }

    fn check_length(&self, len: usize) -> Result<(), OdError> {
        let (key, data_type) = (self.key, self.data_type);
        if data_type.is_variable_length() {
            if let Some(max) = self.max_len.map(usize_from)
                && len > max
            {
                return Err(OdError::LengthTooHigh {
                    key,
                    data_type,
                    len,
                    max,
                });
            }
            if data_type == DataType::UNICODE_STRING && !len.is_multiple_of(2) {
                return Err(OdError::LengthMismatch { key, data_type, len });
            }
            return Ok(());
        }
        // Types that are not basic types keep the length of their first value.
        let expected = data_type.byte_size().unwrap_or(self.value.len());
        match len.cmp(&expected) {
            std::cmp::Ordering::Greater => Err(OdError::LengthTooHigh {
                key,
                data_type,
                len,
                max: expected,
            }),
            std::cmp::Ordering::Less => Err(OdError::LengthTooLow {
                key,
                data_type,
                len,
                expected,
            }),
            std::cmp::Ordering::Equal => Ok(()),
        }
    }

    fn check_limits(&self, data: &[u8]) -> Result<(), OdError> {
        if self.low_limit.is_none() && self.high_limit.is_none() {
            return Ok(());
        }
        // Limits exist only on numeric types and the length was checked, so this decodes.
        let Some(value) = Number::decode(self.data_type, data) else {
            return Ok(());
        };
        if value.is_nan() {
            return Err(OdError::ValueOutOfRange { key: self.key, value });
        }
        if let Some(limit) = self.high_limit()
            && value > limit
        {
            return Err(OdError::ValueTooHigh {
                key: self.key,
                value,
                limit,
            });
        }
        if let Some(limit) = self.low_limit()
            && value < limit
        {
            return Err(OdError::ValueTooLow {
                key: self.key,
                value,
                limit,
            });
        }
        Ok(())
    }

    fn limit_bytes(&self, bytes: &[u8]) -> Result<[u8; 8], EntryError> {
        let (key, data_type) = (self.key, self.data_type);
        let (true, Some(expected)) = (data_type.is_numeric(), data_type.byte_size()) else {
            return Err(EntryError::LimitOnNonNumeric { key, data_type });
        };
        if bytes.len() != expected {
            return Err(EntryError::LimitLength {
                key,
                data_type,
                expected,
                len: bytes.len(),
            });
        }
        if Number::decode(data_type, bytes).is_some_and(Number::is_nan) {
            return Err(EntryError::LimitIsNan { key });
        }
        let mut limit = [0; 8];
        #[allow(
            clippy::indexing_slicing,
            reason = "numeric types are at most 8 bytes, so `expected` fits the buffer"
        )]
        limit[..expected].copy_from_slice(bytes);
        Ok(limit)
    }

    fn decode_limit(&self, limit: [u8; 8]) -> Option<Number> {
        let size = self.data_type.byte_size()?;
        Number::decode(self.data_type, limit.get(..size)?)
    }
}

/// Widens a length; saturating keeps the comparison right on targets with a 16-bit `usize`.
fn usize_from(len: u32) -> usize {
    usize::try_from(len).unwrap_or(usize::MAX)
}

impl fmt::Debug for Entry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut debug = f.debug_struct("Entry");
        debug
            .field("key", &self.key)
            .field("data_type", &self.data_type)
            .field("access", &self.access)
            .field("pdo_mapping", &self.pdo_mapping)
            .field("value", &self.value);
        if self.obj_flags != ObjFlags::NONE {
            debug.field("obj_flags", &self.obj_flags);
        }
        if let Some(low) = self.low_limit() {
            debug.field("low_limit", &low);
        }
        if let Some(high) = self.high_limit() {
            debug.field("high_limit", &high);
        }
        if let Some(max_len) = self.max_len {
            debug.field("max_len", &max_len);
        }
        debug.finish()
    }
}

impl<'a> EntryMut<'a> {
    pub(crate) fn new(entry: &'a mut Entry) -> EntryMut<'a> {
        EntryMut { entry }
    }

    /// Stores `data` with the checks of an SDO download: access type, length and limits.
    /// Nothing changes on error.
    pub fn write(&mut self, data: &[u8]) -> Result<(), OdError> {
        self.entry.write(data)
    }

    /// Stores `data` as the device's own application does, whatever the access type and limits;
    /// only the length must suit the type. Nothing changes on error.
    pub fn set_value(&mut self, data: &[u8]) -> Result<(), OdError> {
        self.entry.set_value(data)
    }

    /// Changes the access type.
    pub fn set_access(&mut self, access: Access) {
        self.entry.access = access;
    }

    /// Changes the `PDOMapping` attribute.
    pub fn set_pdo_mapping(&mut self, pdo_mapping: bool) {
        self.entry.pdo_mapping = pdo_mapping;
    }

    /// Changes the `ObjFlags`.
    pub fn set_obj_flags(&mut self, obj_flags: ObjFlags) {
        self.entry.obj_flags = obj_flags;
    }
}

impl Deref for EntryMut<'_> {
    type Target = Entry;

    fn deref(&self) -> &Entry {
        self.entry
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEY: ObjectKey = ObjectKey::new(0x2000, 1);

    fn entry(data_type: DataType, access: Access, value: &[u8]) -> Entry {
        match Entry::new(KEY, data_type, access, value) {
            Ok(entry) => entry,
            Err(err) => panic!("test entry must build: {err}"),
        }
    }

    fn limited(data_type: DataType, value: &[u8], low: Option<&[u8]>, high: Option<&[u8]>) -> Entry {
        match entry(data_type, Access::Rw, value).with_limits(low, high) {
            Ok(entry) => entry,
            Err(err) => panic!("test limits must build: {err}"),
        }
    }

    #[test]
    fn entry_is_at_most_64_bytes() {
        // The dictionary shifts entries on insert; this keeps a shift cheap and shows up if a
        // field grows by accident.
        assert!(size_of::<Entry>() <= 64, "{}", size_of::<Entry>());
    }

    #[test]
    fn new_checks_fixed_sizes() {
        assert_eq!(
            Entry::new(KEY, DataType::UNSIGNED16, Access::Rw, &[1]),
            Err(EntryError::ValueLength {
                key: KEY,
                data_type: DataType::UNSIGNED16,
                expected: 2,
                len: 1
            })
        );
        assert!(Entry::new(KEY, DataType::INTEGER24, Access::Rw, &[1, 2, 3]).is_ok());
        assert!(Entry::new(KEY, DataType::BOOLEAN, Access::Rw, &[1]).is_ok());
        assert!(Entry::new(KEY, DataType::TIME_OF_DAY, Access::Rw, &[0; 6]).is_ok());
        assert!(Entry::new(KEY, DataType::UNSIGNED56, Access::Rw, &[0; 8]).is_err());
    }

    #[test]
    fn new_accepts_any_length_for_strings_domains_and_opaque_types() {
        assert!(Entry::new(KEY, DataType::VISIBLE_STRING, Access::Ro, b"").is_ok());
        assert!(Entry::new(KEY, DataType::DOMAIN, Access::Rw, &[0; 1000]).is_ok());
        assert!(Entry::new(KEY, DataType(0x0040), Access::Rw, &[0; 5]).is_ok());
        assert_eq!(
            Entry::new(KEY, DataType::UNICODE_STRING, Access::Ro, &[0x41, 0, 0x42]),
            Err(EntryError::UnicodeOddLength { key: KEY, len: 3 })
        );
    }

    #[test]
    fn builders_set_attributes() {
        let built = entry(DataType::UNSIGNED8, Access::Rww, &[7])
            .with_pdo_mapping(true)
            .with_obj_flags(ObjFlags::REFUSE_READ_ON_SCAN);
        assert!(built.pdo_mapping());
        assert!(built.rpdo_mappable());
        assert!(!built.tpdo_mappable());
        assert_eq!(built.obj_flags(), ObjFlags::REFUSE_READ_ON_SCAN);
        assert_eq!(built.number(), Some(Number::Unsigned(7)));
        assert!(!entry(DataType::UNSIGNED8, Access::Rw, &[7]).rpdo_mappable());
    }

    #[test]
    fn limits_are_checked_when_built() {
        let e = || entry(DataType::INTEGER16, Access::Rw, &[0, 0]);
        assert_eq!(
            e().with_limits(Some(&[1]), None),
            Err(EntryError::LimitLength {
                key: KEY,
                data_type: DataType::INTEGER16,
                expected: 2,
                len: 1
            })
        );
        assert_eq!(
            e().with_limits(Some(&5i16.to_le_bytes()), Some(&(-5i16).to_le_bytes())),
            Err(EntryError::LimitsInverted {
                key: KEY,
                low: Number::Signed(5),
                high: Number::Signed(-5)
            })
        );
        assert_eq!(
            entry(DataType::VISIBLE_STRING, Access::Rw, b"x").with_limits(None, Some(b"y")),
            Err(EntryError::LimitOnNonNumeric {
                key: KEY,
                data_type: DataType::VISIBLE_STRING
            })
        );
        assert_eq!(
            entry(DataType::BOOLEAN, Access::Rw, &[0]).with_limits(None, Some(&[1])),
            Err(EntryError::LimitOnNonNumeric {
                key: KEY,
                data_type: DataType::BOOLEAN
            })
        );
        assert_eq!(
            entry(DataType::REAL32, Access::Rw, &[0; 4]).with_limits(Some(&f32::NAN.to_le_bytes()), None),
            Err(EntryError::LimitIsNan { key: KEY })
        );
        let both = limited(
            DataType::INTEGER16,
            &[0, 0],
            Some(&(-5i16).to_le_bytes()),
            Some(&[5, 0]),
        );
        assert_eq!(both.low_limit(), Some(Number::Signed(-5)));
        assert_eq!(both.high_limit(), Some(Number::Signed(5)));
    }

    #[test]
    fn initial_value_may_lie_outside_the_limits() {
        // Real EDS files do this; the limits only bind writes from the network.
        let outside = limited(DataType::UNSIGNED8, &[200], None, Some(&[100]));
        assert_eq!(outside.value(), [200]);
    }

    #[test]
    fn read_refuses_write_only() {
        assert_eq!(
            entry(DataType::UNSIGNED8, Access::Wo, &[1]).read(),
            Err(OdError::WriteOnly { key: KEY })
        );
        for access in [Access::Ro, Access::Rw, Access::Rwr, Access::Rww, Access::Const] {
            assert_eq!(entry(DataType::UNSIGNED8, access, &[1]).read(), Ok(&[1][..]));
        }
    }

    #[test]
    fn write_refuses_read_only_and_const() {
        for access in [Access::Ro, Access::Const] {
            let mut e = entry(DataType::UNSIGNED8, access, &[1]);
            assert_eq!(e.write(&[2]), Err(OdError::ReadOnly { key: KEY, access }));
            assert_eq!(e.value(), [1]);
        }
        for access in [Access::Wo, Access::Rw, Access::Rwr, Access::Rww] {
            let mut e = entry(DataType::UNSIGNED8, access, &[1]);
            assert_eq!(e.write(&[2]), Ok(()));
            assert_eq!(e.value(), [2]);
        }
    }

    #[test]
    fn fixed_size_writes_must_match_exactly() {
        let mut e = entry(DataType::UNSIGNED32, Access::Rw, &[0; 4]);
        assert_eq!(
            e.write(&[0; 5]),
            Err(OdError::LengthTooHigh {
                key: KEY,
                data_type: DataType::UNSIGNED32,
                len: 5,
                max: 4
            })
        );
        assert_eq!(
            e.write(&[0; 2]),
            Err(OdError::LengthTooLow {
                key: KEY,
                data_type: DataType::UNSIGNED32,
                len: 2,
                expected: 4
            })
        );
        assert_eq!(e.write(&[]).map_err(|err| err.abort_code()), Err(0x0607_0013));
        assert_eq!(e.value(), [0; 4]);
    }

    #[test]
    fn opaque_types_keep_their_first_length() {
        let mut e = entry(DataType(0x0040), Access::Rw, &[1, 2, 3]);
        assert_eq!(e.write(&[4, 5, 6]), Ok(()));
        assert_eq!(e.write(&[4, 5]).map_err(|err| err.abort_code()), Err(0x0607_0013));
        assert_eq!(
            e.write(&[4, 5, 6, 7]).map_err(|err| err.abort_code()),
            Err(0x0607_0012)
        );
    }

    #[test]
    fn strings_change_length_up_to_their_maximum() {
        let mut e = entry(DataType::VISIBLE_STRING, Access::Rw, b"hello");
        assert_eq!(e.write(b"hi"), Ok(()));
        assert_eq!(e.value(), b"hi");
        assert_eq!(
            e.write(b"a much longer string than the inline buffer holds"),
            Ok(())
        );
        assert_eq!(e.value(), b"a much longer string than the inline buffer holds");

        let mut bounded = match entry(DataType::VISIBLE_STRING, Access::Rw, b"hello").with_max_len(8) {
            Ok(entry) => entry,
            Err(err) => panic!("{err}"),
        };
        assert_eq!(bounded.write(b"12345678"), Ok(()));
        assert_eq!(
            bounded.write(b"123456789"),
            Err(OdError::LengthTooHigh {
                key: KEY,
                data_type: DataType::VISIBLE_STRING,
                len: 9,
                max: 8
            })
        );
        assert_eq!(bounded.write(b""), Ok(()));
        assert_eq!(bounded.value(), b"");
    }

    #[test]
    fn unicode_strings_take_whole_code_units() {
        let mut e = entry(DataType::UNICODE_STRING, Access::Rw, &[0x41, 0]);
        assert_eq!(
            e.write(&[0x41, 0, 0x42]),
            Err(OdError::LengthMismatch {
                key: KEY,
                data_type: DataType::UNICODE_STRING,
                len: 3
            })
        );
        assert_eq!(e.write(&[0x42, 0, 0x43, 0]), Ok(()));
    }

    #[test]
    fn max_len_only_for_variable_types_and_not_below_the_value() {
        assert_eq!(
            entry(DataType::UNSIGNED8, Access::Rw, &[0]).with_max_len(4),
            Err(EntryError::MaxLenOnFixedSize {
                key: KEY,
                data_type: DataType::UNSIGNED8
            })
        );
        assert_eq!(
            entry(DataType::OCTET_STRING, Access::Rw, &[0; 6]).with_max_len(5),
            Err(EntryError::MaxLenBelowValue {
                key: KEY,
                max_len: 5,
                len: 6
            })
        );
        assert_eq!(
            entry(DataType::DOMAIN, Access::Rw, &[])
                .with_max_len(64)
                .map(|e| e.max_len()),
            Ok(Some(64))
        );
    }

    #[test]
    fn unsigned_limits() {
        let mut e = limited(
            DataType::UNSIGNED16,
            &[10, 0],
            Some(&[10, 0]),
            Some(&[0xE8, 0x03]),
        );
        assert_eq!(e.write(&1000u16.to_le_bytes()), Ok(()));
        assert_eq!(e.write(&10u16.to_le_bytes()), Ok(()));
        assert_eq!(
            e.write(&1001u16.to_le_bytes()),
            Err(OdError::ValueTooHigh {
                key: KEY,
                value: Number::Unsigned(1001),
                limit: Number::Unsigned(1000)
            })
        );
        assert_eq!(
            e.write(&9u16.to_le_bytes()),
            Err(OdError::ValueTooLow {
                key: KEY,
                value: Number::Unsigned(9),
                limit: Number::Unsigned(10)
            })
        );
        assert_eq!(e.number(), Some(Number::Unsigned(10)));
    }

    #[test]
    fn signed_limits_compare_as_signed() {
        // 0xFFFF is -1 for an INTEGER16, so it lies between -10 and 10 although it is "large".
        let mut e = limited(
            DataType::INTEGER16,
            &[0, 0],
            Some(&(-10i16).to_le_bytes()),
            Some(&10i16.to_le_bytes()),
        );
        assert_eq!(e.write(&[0xFF, 0xFF]), Ok(()));
        assert_eq!(e.number(), Some(Number::Signed(-1)));
        assert_eq!(
            e.write(&(-11i16).to_le_bytes()).map_err(|err| err.abort_code()),
            Err(0x0609_0032)
        );
        assert_eq!(
            e.write(&11i16.to_le_bytes()).map_err(|err| err.abort_code()),
            Err(0x0609_0031)
        );
    }

    #[test]
    fn odd_width_limits() {
        let bytes = |value: i64, width: usize| value.to_le_bytes()[..width].to_vec();
        for (data_type, width, low, high) in [
            (DataType::INTEGER24, 3, -(1i64 << 23), -2),
            (DataType::INTEGER40, 5, -(1i64 << 39), (1 << 39) - 2),
            (DataType::INTEGER48, 6, -1000, 1000),
            (DataType::INTEGER56, 7, -(1i64 << 40), 1 << 40),
        ] {
            let mut e = limited(
                data_type,
                &bytes(low, width),
                Some(&bytes(low, width)),
                Some(&bytes(high, width)),
            );
            assert_eq!(e.write(&bytes(high, width)), Ok(()), "{data_type}");
            assert_eq!(
                e.write(&bytes(high + 1, width)).map_err(|err| err.abort_code()),
                Err(0x0609_0031),
                "{data_type}"
            );
            assert_eq!(e.write(&bytes(low, width)), Ok(()), "{data_type}");
            // One below the type's minimum wraps to its maximum, which is above `high`.
            assert!(e.write(&bytes(low - 1, width)).is_err(), "{data_type}");
            assert_eq!(e.number(), Some(Number::Signed(low)), "{data_type}");
        }
        for (data_type, width, low, high) in [
            (DataType::UNSIGNED24, 3, 5u64, 0xFF_FFFE),
            (DataType::UNSIGNED40, 5, 1 << 32, (1 << 40) - 2),
            (DataType::UNSIGNED48, 6, 1, 1 << 47),
            (DataType::UNSIGNED56, 7, 1 << 8, 1 << 50),
        ] {
            let ubytes = |value: u64| value.to_le_bytes()[..width].to_vec();
            let mut e = limited(data_type, &ubytes(low), Some(&ubytes(low)), Some(&ubytes(high)));
            assert_eq!(
                e.write(&ubytes(high + 1)).map_err(|err| err.abort_code()),
                Err(0x0609_0031),
                "{data_type}"
            );
            assert_eq!(
                e.write(&ubytes(low - 1)).map_err(|err| err.abort_code()),
                Err(0x0609_0032),
                "{data_type}"
            );
            assert_eq!(e.write(&ubytes(high)), Ok(()), "{data_type}");
            assert_eq!(e.number(), Some(Number::Unsigned(high)), "{data_type}");
        }
    }

    #[test]
    fn real_limits_and_nan() {
        let mut e = limited(
            DataType::REAL32,
            &0f32.to_le_bytes(),
            Some(&(-1.5f32).to_le_bytes()),
            Some(&1.5f32.to_le_bytes()),
        );
        assert_eq!(e.write(&1.5f32.to_le_bytes()), Ok(()));
        assert_eq!(
            e.write(&1.6f32.to_le_bytes()).map_err(|err| err.abort_code()),
            Err(0x0609_0031)
        );
        assert_eq!(
            e.write(&(-2f32).to_le_bytes()).map_err(|err| err.abort_code()),
            Err(0x0609_0032)
        );
        assert_eq!(
            e.write(&f32::NAN.to_le_bytes()).map_err(|err| err.abort_code()),
            Err(0x0609_0030)
        );
        // Without limits a NaN is just a value.
        let mut free = entry(DataType::REAL64, Access::Rw, &0f64.to_le_bytes());
        assert_eq!(free.write(&f64::NAN.to_le_bytes()), Ok(()));
    }

    #[test]
    fn one_sided_limits() {
        let mut only_high = limited(DataType::INTEGER8, &[0], None, Some(&[0]));
        assert_eq!(only_high.write(&[0x80]), Ok(()));
        assert_eq!(
            only_high.write(&[1]).map_err(|err| err.abort_code()),
            Err(0x0609_0031)
        );
        let mut only_low = limited(
            DataType::UNSIGNED64,
            &[0; 8],
            Some(&[1, 0, 0, 0, 0, 0, 0, 0]),
            None,
        );
        assert_eq!(only_low.write(&[0xFF; 8]), Ok(()));
        assert_eq!(
            only_low.write(&[0; 8]).map_err(|err| err.abort_code()),
            Err(0x0609_0032)
        );
    }

    #[test]
    fn set_value_ignores_access_and_limits_but_not_length() {
        let mut e = limited(DataType::UNSIGNED8, &[1], None, Some(&[10]));
        let mut handle = EntryMut::new(&mut e);
        handle.set_access(Access::Const);
        assert_eq!(handle.set_value(&[200]), Ok(()));
        assert_eq!(handle.value(), [200]);
        assert_eq!(
            handle.set_value(&[1, 2]).map_err(|err| err.abort_code()),
            Err(0x0607_0012)
        );
        assert_eq!(
            handle.write(&[3]).map_err(|err| err.abort_code()),
            Err(0x0601_0002)
        );
        handle.set_pdo_mapping(true);
        handle.set_obj_flags(ObjFlags(1));
        assert_eq!(
            (e.access(), e.pdo_mapping(), e.obj_flags(), e.value()),
            (Access::Const, true, ObjFlags(1), &[200][..])
        );
    }

    #[test]
    fn debug_shows_decoded_limits_and_hex_value() {
        let e = limited(DataType::INTEGER8, &[0xFE], Some(&[0xF0]), None);
        assert_eq!(
            format!("{e:?}"),
            "Entry { key: 0x2000:01, data_type: DataType(INTEGER8), access: Rw, pdo_mapping: false, \
             value: [FE], low_limit: Signed(-16) }"
        );
    }
}
