//! HDF5 Attribute message (type 0x000C).
//!
//! Attributes are small named data items attached to any HDF5 object.
//! Each attribute has a name, datatype, dataspace, and raw data.

use crate::error::{Error, Result};
use crate::io::Cursor;

use super::dataspace::{self, DataspaceMessage, DataspaceType};
use super::datatype::{self, Datatype, DatatypeMessage};
use super::shared::{self, SharedMessage};
use super::{HdfMessage, MSG_DATASPACE, MSG_DATATYPE};

/// Parsed attribute message.
#[derive(Debug, Clone)]
pub struct AttributeMessage {
    /// Attribute name.
    pub name: String,
    /// Datatype of the attribute value.
    pub datatype: Datatype,
    /// Dataspace describing the shape of the attribute data.
    pub dataspace: DataspaceMessage,
    /// Raw attribute data (un-decoded bytes).
    pub raw_data: Vec<u8>,
    /// isotrack: the parts stored elsewhere (flags bit 0: a shared (committed)
    /// datatype, bit 1: a shared dataspace), until [`AttributeMessage::resolve_shared`]
    /// reads them; meanwhile the message is the undecodable placeholder
    /// ([`AttributeMessage::undecodable_reason`]). `None` when all is inline.
    pub(crate) shared: Option<SharedParts>,
}

/// isotrack: the tag of the opaque datatype an attribute that could not be decoded
/// carries (no elements, a null dataspace), followed by the reason. The attribute
/// is kept under its name, so that a reader can tell "absent" from "present but
/// not readable" (netcdf-reader passes it on as an opaque user-defined value).
pub const UNDECODABLE_TAG: &str = "hdf5-reader: undecodable attribute: ";

/// The reason an attribute of `datatype` could not be decoded, when it is the
/// placeholder ([`UNDECODABLE_TAG`]).
pub fn undecodable_reason(datatype: &Datatype) -> Option<&str> {
    match datatype {
        Datatype::Opaque { tag, .. } => tag.strip_prefix(UNDECODABLE_TAG),
        _ => None,
    }
}

/// An attribute's datatype or dataspace: in the message, or a reference to
/// where it is stored (HDF5 specification, "Attribute Message", flags; "Shared
/// Message").
#[derive(Debug, Clone)]
pub(crate) enum Part<T> {
    Inline(T),
    Shared(SharedMessage),
}

/// The parts of an attribute message with a shared datatype or dataspace.
#[derive(Debug, Clone)]
pub(crate) struct SharedParts {
    datatype: Part<DatatypeMessage>,
    dataspace: Part<DataspaceMessage>,
    /// The rest of the message: the value, its size known once the parts are.
    data: Vec<u8>,
}

impl AttributeMessage {
    /// The placeholder for the attribute `name` that could not be decoded:
    /// an opaque datatype tagged [`UNDECODABLE_TAG`] and `reason`, a null
    /// dataspace, no data.
    pub(crate) fn undecodable(name: String, reason: &str) -> Self {
        AttributeMessage {
            name,
            datatype: Datatype::Opaque {
                size: 1,
                tag: format!("{UNDECODABLE_TAG}{reason}"),
            },
            dataspace: DataspaceMessage {
                rank: 0,
                dims: Vec::new(),
                max_dims: None,
                dataspace_type: DataspaceType::Null,
            },
            raw_data: Vec::new(),
            shared: None,
        }
    }

    /// Why the attribute could not be decoded, if it could not (a shared
    /// datatype or dataspace that was not found or not read).
    pub fn undecodable_reason(&self) -> Option<&str> {
        undecodable_reason(&self.datatype)
    }

    /// Whether parts of the attribute are stored elsewhere and not read yet.
    pub(crate) fn has_shared_parts(&self) -> bool {
        self.shared.is_some()
    }

    /// isotrack: read the shared datatype / dataspace with `resolve` (given
    /// the reference, it returns the referenced message), and the value's
    /// bytes from the rest of the message. What cannot be read leaves the
    /// attribute the undecodable placeholder, the reason in its tag.
    pub(crate) fn resolve_shared(
        &mut self,
        mut resolve: impl FnMut(&SharedMessage) -> Result<HdfMessage>,
    ) {
        let Some(parts) = self.shared.take() else {
            return;
        };
        let mut where_from = String::new();
        let resolved = (|| -> Result<(Datatype, DataspaceMessage, Vec<u8>)> {
            let dt = match parts.datatype {
                Part::Inline(dt) => dt,
                Part::Shared(reference) => {
                    where_from = format!("shared datatype {}", describe(&reference));
                    match resolve(&reference)? {
                        HdfMessage::Datatype(dt) => dt,
                        other => {
                            return Err(Error::InvalidData(format!(
                                "found {} instead of a datatype",
                                message_kind(&other)
                            )))
                        }
                    }
                }
            };
            let ds = match parts.dataspace {
                Part::Inline(ds) => ds,
                Part::Shared(reference) => {
                    where_from = format!("shared dataspace {}", describe(&reference));
                    match resolve(&reference)? {
                        HdfMessage::Dataspace(ds) => ds,
                        other => {
                            return Err(Error::InvalidData(format!(
                                "found {} instead of a dataspace",
                                message_kind(&other)
                            )))
                        }
                    }
                }
            };
            where_from = "value".to_string();
            let size = attribute_raw_data_size(&ds, dt.size)?;
            let data = parts.data.get(..size).ok_or_else(|| {
                Error::InvalidData(format!(
                    "needs {size} bytes, the message holds {}",
                    parts.data.len()
                ))
            })?;
            Ok((dt.datatype, ds, data.to_vec()))
        })();
        match resolved {
            Ok((datatype, dataspace, raw_data)) => {
                self.datatype = datatype;
                self.dataspace = dataspace;
                self.raw_data = raw_data;
            }
            Err(e) => {
                let name = std::mem::take(&mut self.name);
                *self = Self::undecodable(name, &format!("{where_from}: {e}"));
            }
        }
    }
}

/// Where a shared message is, for messages.
fn describe(reference: &SharedMessage) -> String {
    match reference {
        SharedMessage::SharedInOhdr { address, .. } => {
            format!("in the object header at {address:#x}")
        }
        SharedMessage::SharedInSohm { .. } => "in the shared message heap".to_string(),
    }
}

/// The kind of a header message, for messages.
fn message_kind(message: &HdfMessage) -> &'static str {
    match message {
        HdfMessage::Datatype(_) => "a datatype",
        HdfMessage::Dataspace(_) => "a dataspace",
        _ => "another message",
    }
}

/// Parse an attribute message.
///
/// Attribute messages embed inline datatype and dataspace descriptions
/// followed by the raw data bytes.
pub fn parse(
    cursor: &mut Cursor<'_>,
    offset_size: u8,
    length_size: u8,
    msg_size: usize,
) -> Result<AttributeMessage> {
    // The embedded datatype, dataspace and data must lie within the message:
    // parse from the message's own bytes, never from the messages after it.
    let mut message = Cursor::new(cursor.read_bytes(msg_size)?);
    let version = message.read_u8()?;
    match version {
        1 => parse_v1(&mut message, offset_size, length_size),
        2 => parse_v2(&mut message, offset_size, length_size),
        3 => parse_v3(&mut message, offset_size, length_size),
        v => Err(Error::UnsupportedAttributeVersion(v)),
    }
}

fn parse_v1(cursor: &mut Cursor<'_>, offset_size: u8, length_size: u8) -> Result<AttributeMessage> {
    let _reserved = cursor.read_u8()?;
    let name_size = cursor.read_u16_le()? as usize;
    let datatype_size = cursor.read_u16_le()? as usize;
    let dataspace_size = cursor.read_u16_le()? as usize;

    // Name — padded to 8-byte boundary
    let name = cursor.read_fixed_string(name_size)?;
    let name_padded = (name_size + 7) & !7;
    if name_padded > name_size {
        cursor.skip(name_padded - name_size)?;
    }

    // Datatype — padded to 8
    let dt_start = cursor.position();
    let dt_msg = datatype::parse(cursor, datatype_size)?;
    if let Some(raw) = super::raw_bytes(cursor, dt_start, datatype_size) {
        super::record_attribute_datatype(&name, raw);
    }
    let dt_consumed = datatype_size; // parse() already handles its own size
    let dt_padded = (dt_consumed + 7) & !7;
    if dt_padded > dt_consumed {
        cursor.skip(dt_padded - dt_consumed)?;
    }

    // Dataspace — padded to 8
    let ds_msg = dataspace::parse(cursor, offset_size, length_size, dataspace_size)?;
    let ds_consumed = dataspace_size;
    let ds_padded = (ds_consumed + 7) & !7;
    if ds_padded > ds_consumed {
        cursor.skip(ds_padded - ds_consumed)?;
    }

    // Raw data — remaining bytes are the attribute data
    let data_size = attribute_raw_data_size(&ds_msg, dt_msg.size)?;
    let raw_data = if data_size > 0 {
        cursor.read_bytes(data_size)?.to_vec()
    } else {
        vec![]
    };

    Ok(AttributeMessage {
        name,
        datatype: dt_msg.datatype,
        dataspace: ds_msg,
        raw_data,
        shared: None,
    })
}

fn parse_v2(cursor: &mut Cursor<'_>, offset_size: u8, length_size: u8) -> Result<AttributeMessage> {
    let flags = cursor.read_u8()?;
    check_flags(flags, 2)?;
    let name_size = cursor.read_u16_le()? as usize;
    let datatype_size = cursor.read_u16_le()? as usize;
    let dataspace_size = cursor.read_u16_le()? as usize;

    // Name — NOT padded in v2
    let name = cursor.read_fixed_string(name_size)?;

    if flags != 0 {
        return Ok(parse_shared_parts(
            cursor,
            name,
            flags,
            offset_size,
            length_size,
            datatype_size,
            dataspace_size,
        ));
    }

    // Datatype
    let dt_start = cursor.position();
    let dt_msg = datatype::parse(cursor, datatype_size)?;
    if let Some(raw) = super::raw_bytes(cursor, dt_start, datatype_size) {
        super::record_attribute_datatype(&name, raw);
    }

    // Dataspace
    let ds_msg = dataspace::parse(cursor, offset_size, length_size, dataspace_size)?;

    // Raw data
    let data_size = attribute_raw_data_size(&ds_msg, dt_msg.size)?;
    let raw_data = if data_size > 0 {
        cursor.read_bytes(data_size)?.to_vec()
    } else {
        vec![]
    };

    Ok(AttributeMessage {
        name,
        datatype: dt_msg.datatype,
        dataspace: ds_msg,
        raw_data,
        shared: None,
    })
}

fn parse_v3(cursor: &mut Cursor<'_>, offset_size: u8, length_size: u8) -> Result<AttributeMessage> {
    let flags = cursor.read_u8()?;
    let name_size = cursor.read_u16_le()? as usize;
    let datatype_size = cursor.read_u16_le()? as usize;
    let dataspace_size = cursor.read_u16_le()? as usize;
    let _name_encoding = cursor.read_u8()?;
    check_flags(flags, 3)?;

    // Name — NOT padded in v3
    let name = cursor.read_fixed_string(name_size)?;

    if flags != 0 {
        return Ok(parse_shared_parts(
            cursor,
            name,
            flags,
            offset_size,
            length_size,
            datatype_size,
            dataspace_size,
        ));
    }

    // Datatype
    let dt_start = cursor.position();
    let dt_msg = datatype::parse(cursor, datatype_size)?;
    if let Some(raw) = super::raw_bytes(cursor, dt_start, datatype_size) {
        super::record_attribute_datatype(&name, raw);
    }

    // Dataspace
    let ds_msg = dataspace::parse(cursor, offset_size, length_size, dataspace_size)?;

    // Raw data
    let data_size = attribute_raw_data_size(&ds_msg, dt_msg.size)?;
    let raw_data = if data_size > 0 {
        cursor.read_bytes(data_size)?.to_vec()
    } else {
        vec![]
    };

    Ok(AttributeMessage {
        name,
        datatype: dt_msg.datatype,
        dataspace: ds_msg,
        raw_data,
        shared: None,
    })
}

/// Version 2 and 3 attribute flags: bit 0 marks a shared datatype, bit 1 a
/// shared dataspace; the other bits are reserved.
fn check_flags(flags: u8, version: u8) -> Result<()> {
    if flags & !0x03 != 0 {
        return Err(Error::InvalidData(format!(
            "reserved flags {flags:#04x} in attribute v{version}"
        )));
    }
    Ok(())
}

/// A shared message of `size` bytes, within them.
fn parse_reference(
    cursor: &mut Cursor<'_>,
    message_type: u16,
    offset_size: u8,
    length_size: u8,
    size: usize,
) -> Result<SharedMessage> {
    let mut field = Cursor::new(cursor.read_bytes(size)?);
    shared::parse(&mut field, message_type, offset_size, length_size, size)
}

/// isotrack: the rest of a version 2 or 3 attribute message whose datatype
/// (flags bit 0) or dataspace (bit 1) is shared: that field holds a shared
/// message (where the datatype or dataspace is stored) instead of the
/// datatype or dataspace itself. The attribute is the undecodable placeholder
/// until [`AttributeMessage::resolve_shared`] reads the parts; a field that
/// cannot be parsed leaves it the placeholder for good (the rest of the file
/// is still read: the attribute may be one nobody needs).
fn parse_shared_parts(
    cursor: &mut Cursor<'_>,
    name: String,
    flags: u8,
    offset_size: u8,
    length_size: u8,
    datatype_size: usize,
    dataspace_size: usize,
) -> AttributeMessage {
    let mut where_from = "shared datatype reference";
    let parts = (|| -> Result<SharedParts> {
        let datatype = if flags & 0x01 != 0 {
            Part::Shared(parse_reference(
                cursor,
                MSG_DATATYPE,
                offset_size,
                length_size,
                datatype_size,
            )?)
        } else {
            where_from = "datatype";
            let dt_start = cursor.position();
            let dt = datatype::parse(cursor, datatype_size)?;
            if let Some(raw) = super::raw_bytes(cursor, dt_start, datatype_size) {
                super::record_attribute_datatype(&name, raw);
            }
            Part::Inline(dt)
        };
        let dataspace = if flags & 0x02 != 0 {
            where_from = "shared dataspace reference";
            Part::Shared(parse_reference(
                cursor,
                MSG_DATASPACE,
                offset_size,
                length_size,
                dataspace_size,
            )?)
        } else {
            where_from = "dataspace";
            Part::Inline(dataspace::parse(
                cursor,
                offset_size,
                length_size,
                dataspace_size,
            )?)
        };
        let data = cursor.read_bytes(cursor.remaining() as usize)?.to_vec();
        Ok(SharedParts {
            datatype,
            dataspace,
            data,
        })
    })();
    match parts {
        Ok(parts) => {
            let mut msg = AttributeMessage::undecodable(
                name,
                "shared datatype or dataspace not read (no file to read it from)",
            );
            msg.shared = Some(parts);
            msg
        }
        Err(e) => AttributeMessage::undecodable(name, &format!("{where_from}: {e}")),
    }
}

fn attribute_raw_data_size(ds_msg: &dataspace::DataspaceMessage, dtype_size: u32) -> Result<usize> {
    let elements = usize::try_from(ds_msg.num_elements()?).map_err(|_| {
        Error::InvalidData("attribute element count exceeds platform usize capacity".to_string())
    })?;
    elements.checked_mul(dtype_size as usize).ok_or_else(|| {
        Error::InvalidData("attribute raw data size exceeds platform usize capacity".to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ByteOrder;
    use crate::messages::dataspace::DataspaceType;

    /// Build a minimal u32-LE datatype description (8 bytes total: 4 class/ver/flags + 4 size).
    fn u32_le_datatype() -> Vec<u8> {
        let mut buf = Vec::new();
        // class=0, version=1, flags=0 (LE unsigned)
        let class_word: u32 = 0x01 << 4;
        buf.extend_from_slice(&class_word.to_le_bytes());
        buf.extend_from_slice(&4u32.to_le_bytes()); // size=4
                                                    // properties: offset=0, precision=32
        buf.extend_from_slice(&0u16.to_le_bytes());
        buf.extend_from_slice(&32u16.to_le_bytes());
        buf
    }

    /// Build a scalar dataspace (v2, rank=0, type=scalar).
    fn scalar_dataspace() -> Vec<u8> {
        vec![0x02, 0x00, 0x00, 0x00]
    }

    /// A version 2 or 3 scalar u32 attribute "abc" = 99.
    fn attr(version: u8, flags: u8) -> Vec<u8> {
        let dt = u32_le_datatype();
        let ds = scalar_dataspace();
        let mut data = vec![version, flags];
        data.extend_from_slice(&4u16.to_le_bytes());
        data.extend_from_slice(&(dt.len() as u16).to_le_bytes());
        data.extend_from_slice(&(ds.len() as u16).to_le_bytes());
        if version == 3 {
            data.push(0x00); // ASCII name
        }
        data.extend_from_slice(b"abc\0");
        data.extend_from_slice(&dt);
        data.extend_from_slice(&ds);
        data.extend_from_slice(&99u32.to_le_bytes());
        data
    }

    #[test]
    fn reserved_and_shared_attribute_flags_are_refused() {
        for version in [2, 3] {
            let data = attr(version, 0);
            assert_eq!(
                parse(&mut Cursor::new(&data), 8, 8, data.len())
                    .unwrap()
                    .raw_data,
                99u32.to_le_bytes()
            );
            for flags in [0x04, 0x80] {
                let data = attr(version, flags);
                let err = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap_err();
                assert!(
                    err.to_string().contains("reserved flags"),
                    "v{version}: {err}"
                );
            }
            // Shared datatype or dataspace: the inline fields are not there, and
            // these are no shared messages either (version 0x10 / 0x02 with type
            // 0): the attribute is kept, undecodable, under its name.
            for flags in [0x01, 0x02, 0x03] {
                let data = attr(version, flags);
                let msg = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
                assert_eq!(msg.name, "abc");
                let reason = msg.undecodable_reason().expect("undecodable");
                assert!(reason.contains("shared"), "v{version}: {reason}");
                assert!(msg.raw_data.is_empty());
                assert_eq!(msg.dataspace.num_elements().unwrap(), 0);
            }
        }
    }

    #[test]
    fn attribute_is_parsed_within_its_message() {
        let data = attr(3, 0);

        // The value runs two bytes past the declared message size: an error,
        // not two bytes of the next message.
        let mut overrun = data.clone();
        overrun.extend_from_slice(&[0xaa; 8]);
        let mut cursor = Cursor::new(&overrun);
        assert!(parse(&mut cursor, 8, 8, data.len() - 2).is_err());

        // Trailing padding inside the message is skipped.
        let mut padded = data.clone();
        padded.extend_from_slice(&[0; 4]);
        padded.extend_from_slice(&[0xaa; 4]);
        let mut cursor = Cursor::new(&padded);
        let msg = parse(&mut cursor, 8, 8, data.len() + 4).unwrap();
        assert_eq!(msg.raw_data, 99u32.to_le_bytes());
        assert_eq!(cursor.position() as usize, data.len() + 4);
    }

    #[test]
    fn datatype_larger_than_its_message_is_refused() {
        let dt = u32_le_datatype();
        assert!(datatype::parse(&mut Cursor::new(&dt), dt.len()).is_ok());
        let err = datatype::parse(&mut Cursor::new(&dt), dt.len() - 4).unwrap_err();
        assert!(err.to_string().contains("exceeds"), "{err}");
    }

    #[test]
    fn parse_v1_scalar_u32_attr() {
        let dt = u32_le_datatype();
        let ds = scalar_dataspace();

        let mut data = vec![
            0x01, // version 1
            0x00, // reserved
        ];
        // name size = 5 ("temp\0")
        data.extend_from_slice(&5u16.to_le_bytes());
        // datatype size
        data.extend_from_slice(&(dt.len() as u16).to_le_bytes());
        // dataspace size
        data.extend_from_slice(&(ds.len() as u16).to_le_bytes());

        // Name "temp\0" padded to 8 bytes
        data.extend_from_slice(b"temp\0\0\0\0");

        // Datatype (12 bytes), padded to 16
        data.extend_from_slice(&dt);
        data.extend_from_slice(&[0u8; 4]); // padding to 16

        // Dataspace (4 bytes), padded to 8
        data.extend_from_slice(&ds);
        data.extend_from_slice(&[0u8; 4]); // padding to 8

        // Raw data: 1 scalar element * 4 bytes
        data.extend_from_slice(&42u32.to_le_bytes());

        let mut cursor = Cursor::new(&data);
        let msg = parse(&mut cursor, 8, 8, data.len()).unwrap();
        assert_eq!(msg.name, "temp");
        assert_eq!(msg.dataspace.dataspace_type, DataspaceType::Scalar);
        assert_eq!(msg.raw_data, 42u32.to_le_bytes());
        match &msg.datatype {
            Datatype::FixedPoint {
                size: 4,
                signed: false,
                byte_order: ByteOrder::LittleEndian,
            } => {}
            other => panic!("unexpected datatype: {:?}", other),
        }
    }

    fn v3_attr(flags: u8) -> Vec<u8> {
        let dt = u32_le_datatype();
        let ds = scalar_dataspace();
        let mut data = vec![0x03, flags];
        data.extend_from_slice(&4u16.to_le_bytes());
        data.extend_from_slice(&(dt.len() as u16).to_le_bytes());
        data.extend_from_slice(&(ds.len() as u16).to_le_bytes());
        data.push(0x00);
        data.extend_from_slice(b"abc\0");
        data.extend_from_slice(&dt);
        data.extend_from_slice(&ds);
        data.extend_from_slice(&99u32.to_le_bytes());
        data
    }

    #[test]
    fn shared_v3_attribute_encodings_are_undecodable_not_refused() {
        for flags in [1, 2, 3] {
            let data = v3_attr(flags);
            let mut msg = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
            assert!(msg.undecodable_reason().is_some());
            // Nothing to resolve: the references themselves did not parse.
            assert!(!msg.has_shared_parts());
            msg.resolve_shared(|_| panic!("nothing to resolve"));
            assert!(msg.undecodable_reason().is_some());
        }
    }

    /// A version 3 attribute "abc" with a committed datatype at 0x1234 (a
    /// shared message v3, type 2, 8-byte address, as libhdf5 writes it), a
    /// scalar dataspace and the value 99u32, `pad` bytes after it.
    fn committed_attr(version: u8, pad: usize) -> Vec<u8> {
        let mut reference = vec![3, 2];
        reference.extend_from_slice(&0x1234u64.to_le_bytes());
        let ds = scalar_dataspace();
        let mut data = vec![version, 0x01];
        data.extend_from_slice(&4u16.to_le_bytes());
        data.extend_from_slice(&(reference.len() as u16).to_le_bytes());
        data.extend_from_slice(&(ds.len() as u16).to_le_bytes());
        if version == 3 {
            data.push(0x00);
        }
        data.extend_from_slice(b"abc\0");
        data.extend_from_slice(&reference);
        data.extend_from_slice(&ds);
        data.extend_from_slice(&99u32.to_le_bytes());
        data.extend(std::iter::repeat(0xee).take(pad));
        data
    }

    fn u32_message() -> HdfMessage {
        let dt = u32_le_datatype();
        HdfMessage::Datatype(datatype::parse(&mut Cursor::new(&dt), dt.len()).unwrap())
    }

    #[test]
    fn committed_datatype_is_read_from_where_it_is_stored() {
        for version in [2, 3] {
            let data = committed_attr(version, 3);
            let mut msg = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
            assert!(msg.has_shared_parts());
            // Until resolved, the placeholder: never the reference's bytes as a value.
            assert!(msg.undecodable_reason().is_some());
            let mut asked = Vec::new();
            msg.resolve_shared(|reference| {
                asked.push(format!("{reference:?}"));
                Ok(u32_message())
            });
            assert_eq!(asked.len(), 1);
            assert!(asked[0].contains("address: 4660"), "{asked:?}");
            assert_eq!(msg.name, "abc");
            assert_eq!(msg.undecodable_reason(), None);
            assert!(!msg.has_shared_parts());
            assert_eq!(msg.dataspace.dataspace_type, DataspaceType::Scalar);
            // The value's 4 bytes, not the padding after them.
            assert_eq!(msg.raw_data, 99u32.to_le_bytes());
        }
    }

    #[test]
    fn committed_datatype_that_cannot_be_read_leaves_the_attribute_undecodable() {
        let data = committed_attr(3, 0);
        // Not found.
        let mut msg = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
        msg.resolve_shared(|_| Err(Error::InvalidData("no header there".into())));
        assert_eq!(msg.name, "abc");
        let reason = msg.undecodable_reason().unwrap();
        assert!(reason.contains("0x1234"), "{reason}");
        assert!(reason.contains("no header there"), "{reason}");
        assert!(msg.raw_data.is_empty());
        // Something else stored there.
        let mut msg = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
        msg.resolve_shared(|_| {
            Ok(HdfMessage::Dataspace(
                dataspace::parse(&mut Cursor::new(&scalar_dataspace()), 8, 8, 4).unwrap(),
            ))
        });
        assert!(msg
            .undecodable_reason()
            .unwrap()
            .contains("instead of a datatype"));
        // A datatype larger than the value stored: 8 bytes wanted, 4 there.
        let mut msg = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
        msg.resolve_shared(|_| {
            let mut dt = u32_le_datatype();
            dt[4..8].copy_from_slice(&8u32.to_le_bytes());
            Ok(HdfMessage::Datatype(
                datatype::parse(&mut Cursor::new(&dt), dt.len()).unwrap(),
            ))
        });
        let reason = msg.undecodable_reason().unwrap();
        assert!(reason.contains("needs 8 bytes"), "{reason}");
    }

    #[test]
    fn shared_reference_longer_than_its_field_is_undecodable() {
        // The datatype field declared 4 bytes: the 10-byte reference runs into
        // the dataspace.
        let mut data = committed_attr(3, 0);
        data[4..6].copy_from_slice(&4u16.to_le_bytes());
        let msg = parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
        assert!(!msg.has_shared_parts());
        assert!(msg.undecodable_reason().is_some());
    }

    #[test]
    fn attribute_datatype_bytes_are_recorded_only_while_capturing() {
        let data = v3_attr(0);
        parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();

        let outer = crate::messages::RawCapture::start();
        let inner = crate::messages::RawCapture::start();
        parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
        let captured = inner.finish();
        assert_eq!(
            captured.attributes,
            vec![("abc".to_string(), u32_le_datatype())]
        );
        // The outer capture is active again and saw nothing of the inner one.
        parse(&mut Cursor::new(&data), 8, 8, data.len()).unwrap();
        assert_eq!(outer.finish().attributes.len(), 1);

        // A capture dropped without finishing leaves none active.
        drop(crate::messages::RawCapture::start());
        let after = crate::messages::RawCapture::start();
        assert!(after.finish().attributes.is_empty());
    }

    #[test]
    fn parse_v3_scalar_attr() {
        let dt = u32_le_datatype();
        let ds = scalar_dataspace();

        let mut data = vec![
            0x03, // version 3
            0x00, // flags
        ];
        // name size = 4 ("abc\0")
        data.extend_from_slice(&4u16.to_le_bytes());
        data.extend_from_slice(&(dt.len() as u16).to_le_bytes());
        data.extend_from_slice(&(ds.len() as u16).to_le_bytes());
        data.push(0x00); // ASCII name encoding

        // Name (not padded in v3)
        data.extend_from_slice(b"abc\0");

        // Datatype
        data.extend_from_slice(&dt);

        // Dataspace
        data.extend_from_slice(&ds);

        // Raw data
        data.extend_from_slice(&99u32.to_le_bytes());

        let mut cursor = Cursor::new(&data);
        let msg = parse(&mut cursor, 8, 8, data.len()).unwrap();
        assert_eq!(msg.name, "abc");
        assert_eq!(msg.dataspace.dataspace_type, DataspaceType::Scalar);
        assert_eq!(msg.raw_data, 99u32.to_le_bytes());
    }

    #[test]
    fn parse_v3_utf8_name_attr() {
        let dt = u32_le_datatype();
        let ds = scalar_dataspace();

        let mut data = vec![
            0x03, // version 3
            0x00, // flags
        ];
        data.extend_from_slice(&2u16.to_le_bytes()); // "x\0"
        data.extend_from_slice(&(dt.len() as u16).to_le_bytes());
        data.extend_from_slice(&(ds.len() as u16).to_le_bytes());
        data.push(0x01); // UTF-8 name encoding
        data.extend_from_slice(b"x\0");
        data.extend_from_slice(&dt);
        data.extend_from_slice(&ds);
        data.extend_from_slice(&7u32.to_le_bytes());

        let mut cursor = Cursor::new(&data);
        let msg = parse(&mut cursor, 8, 8, data.len()).unwrap();
        assert_eq!(msg.name, "x");
        assert_eq!(msg.dataspace.dataspace_type, DataspaceType::Scalar);
        assert_eq!(msg.raw_data, 7u32.to_le_bytes());
    }
}
