//! Shared object-header message table (SOHM).
//!
//! The superblock extension can point at a file-level `SMTB` table containing
//! one or more shared-message indexes. Each index is either an `SMLI` list or
//! a v2 B-tree with record type 7.

use std::sync::Arc;

use crate::checksum::jenkins_lookup3;
use crate::error::{Error, Result};
use crate::filters::FilterRegistry;
use crate::fractal_heap::FractalHeap;
use crate::io::Cursor;
use crate::messages::{parse_message, HdfMessage};
use crate::storage::Storage;

const SMTB_SIGNATURE: [u8; 4] = *b"SMTB";
#[cfg(test)]
const SMLI_SIGNATURE: [u8; 4] = *b"SMLI";

/// File-level SOHM master table.
#[derive(Debug, Clone)]
pub(crate) struct SharedMessageTable {
    indexes: Vec<SharedMessageIndex>,
}

// isotrack: reading a shared message needs only the index's flags and heap
// address (the rest is kept as the table holds it); list records are parsed
// by the unit tests only.
#[allow(dead_code)]
#[derive(Debug, Clone)]
struct SharedMessageIndex {
    index_type: SharedMessageIndexType,
    message_type_flags: u16,
    min_message_size: u32,
    list_cutoff: u16,
    btree_cutoff: u16,
    num_messages: u16,
    index_address: u64,
    fractal_heap_address: u64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SharedMessageIndexType {
    List,
    BTree,
}

#[cfg(test)]
#[allow(dead_code)]
#[derive(Debug, Clone)]
enum SharedMessageRecord {
    Heap {
        hash: u32,
        reference_count: u32,
        heap_id: Vec<u8>,
    },
    ObjectHeader {
        hash: u32,
        message_type: u16,
        object_header_index: u16,
        object_header_address: u64,
    },
}

impl SharedMessageTable {
    /// Parse a SOHM master table from storage.
    pub(crate) fn parse_at_storage(
        storage: &dyn Storage,
        address: u64,
        num_indices: u8,
        offset_size: u8,
    ) -> Result<Self> {
        // isotrack: an index header is version, type, message type flags, minimum size, list
        // and B-tree cutoffs, message count, then the two addresses, packed (libhdf5's
        // `H5SM__cache_table_deserialize`); 0.12.1 read 2 reserved bytes after the count.
        let entry_len = 1 + 1 + 2 + 4 + 2 + 2 + 2 + usize::from(offset_size) * 2;
        let table_len = 4 + usize::from(num_indices) * entry_len + 4;
        let bytes = storage.read_range(address, table_len)?;
        let mut cursor = Cursor::new(bytes.as_ref());
        let sig = cursor.read_bytes(4)?;
        if sig != SMTB_SIGNATURE {
            return Err(Error::InvalidData(format!(
                "expected SMTB signature at offset {address:#x}"
            )));
        }

        let mut indexes = Vec::with_capacity(usize::from(num_indices));
        for _ in 0..num_indices {
            let version = cursor.read_u8()?;
            if version != 0 {
                return Err(Error::InvalidData(format!(
                    "unsupported SOHM index version: {version}"
                )));
            }
            let index_type = match cursor.read_u8()? {
                0 => SharedMessageIndexType::List,
                1 => SharedMessageIndexType::BTree,
                other => {
                    return Err(Error::InvalidData(format!(
                        "unsupported SOHM index type: {other}"
                    )))
                }
            };
            let message_type_flags = cursor.read_u16_le()?;
            let min_message_size = cursor.read_u32_le()?;
            let list_cutoff = cursor.read_u16_le()?;
            let btree_cutoff = cursor.read_u16_le()?;
            let num_messages = cursor.read_u16_le()?;
            let index_address = cursor.read_offset(offset_size)?;
            let fractal_heap_address = cursor.read_offset(offset_size)?;
            indexes.push(SharedMessageIndex {
                index_type,
                message_type_flags,
                min_message_size,
                list_cutoff,
                btree_cutoff,
                num_messages,
                index_address,
                fractal_heap_address,
            });
        }

        let checksum_pos = cursor.position() as usize;
        let stored_checksum = cursor.read_u32_le()?;
        let computed = jenkins_lookup3(&bytes.as_ref()[..checksum_pos]);
        if computed != stored_checksum {
            return Err(Error::ChecksumMismatch {
                expected: stored_checksum,
                actual: computed,
            });
        }

        Ok(Self { indexes })
    }

    /// Resolve a SOHM heap ID into the concrete object-header message.
    ///
    /// isotrack: the heap ID is an object ID in the fractal heap of the one
    /// index whose message-type flags hold `message_type` (libhdf5's
    /// `H5SM_get_fheap_addr`, then `H5HF_op`; the index's records are not
    /// needed to read it). 0.12.1 tested the flags with the wrong bits (see
    /// [`shared_message_type_flag`]), fell back to every index when none
    /// matched and took the first record with an equal heap ID: heap IDs are
    /// unique only within one heap, so with datatypes and dataspaces in
    /// separate indexes a datatype was read from the dataspace heap ("unsupported
    /// dataspace version 17"). `None` when no index tracks the type.
    pub(crate) fn resolve_heap_message(
        &self,
        heap_id: &[u8],
        message_type: u16,
        storage: &dyn Storage,
        offset_size: u8,
        length_size: u8,
        filter_registry: Option<&FilterRegistry>,
    ) -> Result<Option<HdfMessage>> {
        let Some(index) = self
            .indexes
            .iter()
            .find(|index| index.tracks_message_type(message_type))
        else {
            return Ok(None);
        };
        if Cursor::is_undefined_offset(index.fractal_heap_address, offset_size) {
            return Err(Error::UndefinedAddress);
        }
        let heap = FractalHeap::parse_at_storage(
            storage,
            index.fractal_heap_address,
            offset_size,
            length_size,
        )?;
        let payload = heap.get_object_storage_with_registry(
            heap_id,
            storage,
            offset_size,
            length_size,
            filter_registry,
        )?;
        let mut cursor = Cursor::new(&payload);
        let message = parse_message(
            message_type,
            payload.len(),
            &mut cursor,
            offset_size,
            length_size,
        )?;
        Ok(Some(message))
    }
}

impl SharedMessageIndex {
    fn tracks_message_type(&self, message_type: u16) -> bool {
        let Some(flag) = shared_message_type_flag(message_type) else {
            return false;
        };
        (self.message_type_flags & flag) != 0
    }
}

#[cfg(test)]
fn parse_record_list(
    storage: &dyn Storage,
    address: u64,
    num_records: u16,
    offset_size: u8,
) -> Result<Vec<SharedMessageRecord>> {
    if num_records == 0 {
        return Ok(Vec::new());
    }
    // isotrack: each entry takes the record's size, `record_len` (libhdf5's
    // `H5SM_SOHM_ENTRY_SIZE`), whichever its location; 0.12.1 read 20 bytes per record.
    let max_len = 4 + usize::from(num_records) * record_len(offset_size) + 4;
    let bytes = storage.read_range(address, max_len)?;
    let mut cursor = Cursor::new(bytes.as_ref());
    let sig = cursor.read_bytes(4)?;
    if sig != SMLI_SIGNATURE {
        return Err(Error::InvalidData(format!(
            "expected SMLI signature at offset {address:#x}"
        )));
    }

    let mut records = Vec::with_capacity(usize::from(num_records));
    for _ in 0..num_records {
        let start = cursor.position() as usize;
        records.push(parse_record(&mut cursor, offset_size)?);
        let end = start + record_len(offset_size);
        cursor.skip(end - cursor.position() as usize)?;
    }

    let checksum_pos = cursor.position() as usize;
    let stored_checksum = cursor.read_u32_le()?;
    let computed = jenkins_lookup3(&bytes.as_ref()[..checksum_pos]);
    if computed != stored_checksum {
        return Err(Error::ChecksumMismatch {
            expected: stored_checksum,
            actual: computed,
        });
    }

    Ok(records)
}

#[cfg(test)]
/// The size of one shared-message record in a list or B-tree index, bytes: location (1),
/// hash (4), then the larger of a heap record (reference count 4, heap ID 8) and an
/// object-header record (reserved 1, message type 1, index 2, address): libhdf5's
/// `H5SM_SOHM_ENTRY_SIZE` (17 with 8-byte offsets).
pub(crate) fn record_len(offset_size: u8) -> usize {
    1 + 4 + 12usize.max(4 + usize::from(offset_size))
}

#[cfg(test)]
fn parse_record(cursor: &mut Cursor<'_>, offset_size: u8) -> Result<SharedMessageRecord> {
    // isotrack: location then hash, packed (libhdf5's `H5SM__message_decode`; the
    // specification's table shows padding that is not in the file): 0.12.1 skipped 3 bytes.
    let location = cursor.read_u8()?;
    let hash = cursor.read_u32_le()?;
    match location {
        0 => {
            let reference_count = cursor.read_u32_le()?;
            let heap_id = cursor.read_bytes(8)?.to_vec();
            Ok(SharedMessageRecord::Heap {
                hash,
                reference_count,
                heap_id,
            })
        }
        1 => {
            let _reserved = cursor.read_u8()?;
            let message_type = u16::from(cursor.read_u8()?);
            let object_header_index = cursor.read_u16_le()?;
            let object_header_address = cursor.read_offset(offset_size)?;
            Ok(SharedMessageRecord::ObjectHeader {
                hash,
                message_type,
                object_header_index,
                object_header_address,
            })
        }
        other => Err(Error::InvalidData(format!(
            "unknown SOHM record location: {other}"
        ))),
    }
}

/// isotrack: the flag of `message_type` in an index's message-type flags:
/// `1 << message type ID` (HDF5 file format specification, "Shared Object
/// Header Message Table", the index's "Message Type Flags": bit 1 dataspace
/// 0x0001, bit 3 datatype 0x0003, bit 5 fill value 0x0005, bit 11 filter
/// pipeline 0x000B, bit 12 attribute 0x000C; libhdf5's `H5O_SHMESG_*_FLAG`,
/// every kind 0x182A). 0.12.1 used bits 0 to 4. The old fill value message
/// (0x0004) is looked up in the fill value index.
fn shared_message_type_flag(message_type: u16) -> Option<u16> {
    use crate::messages::{
        MSG_ATTRIBUTE, MSG_DATASPACE, MSG_DATATYPE, MSG_FILL_VALUE, MSG_FILL_VALUE_OLD,
        MSG_FILTER_PIPELINE,
    };
    match message_type {
        MSG_DATASPACE | MSG_DATATYPE | MSG_FILL_VALUE | MSG_FILTER_PIPELINE | MSG_ATTRIBUTE => {
            Some(1u16 << message_type)
        }
        MSG_FILL_VALUE_OLD => Some(1u16 << MSG_FILL_VALUE),
        _ => None,
    }
}

pub(crate) type SharedMessageTableRef = Arc<SharedMessageTable>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::BytesStorage;

    #[test]
    fn parses_master_table() {
        let mut table = Vec::new();
        table.extend_from_slice(b"SMTB");
        table.push(0);
        table.push(0);
        table.extend_from_slice(&0x0008u16.to_le_bytes());
        table.extend_from_slice(&16u32.to_le_bytes());
        table.extend_from_slice(&8u16.to_le_bytes());
        table.extend_from_slice(&6u16.to_le_bytes());
        table.extend_from_slice(&1u16.to_le_bytes());
        table.extend_from_slice(&64u64.to_le_bytes());
        table.extend_from_slice(&128u64.to_le_bytes());
        let checksum = jenkins_lookup3(&table);
        table.extend_from_slice(&checksum.to_le_bytes());

        let storage = BytesStorage::new(table);
        let parsed = SharedMessageTable::parse_at_storage(&storage, 0, 1, 8).unwrap();
        assert_eq!(parsed.indexes.len(), 1);
        assert!(parsed.indexes[0].tracks_message_type(crate::messages::MSG_DATATYPE));
        assert!(!parsed.indexes[0].tracks_message_type(crate::messages::MSG_DATASPACE));
        assert_eq!(parsed.indexes[0].num_messages, 1);
        assert_eq!(parsed.indexes[0].index_address, 64);
        assert_eq!(parsed.indexes[0].fractal_heap_address, 128);
    }

    /// isotrack: libhdf5's `H5O_SHMESG_*_FLAG` values (H5Opublic.h), 1 << message type ID.
    #[test]
    fn index_flags_are_one_shifted_by_the_message_type() {
        use crate::messages::*;
        let index = |flags| SharedMessageIndex {
            index_type: SharedMessageIndexType::List,
            message_type_flags: flags,
            min_message_size: 0,
            list_cutoff: 50,
            btree_cutoff: 40,
            num_messages: 0,
            index_address: 0,
            fractal_heap_address: 0,
        };
        let kinds = [
            (MSG_DATASPACE, 0x0002),
            (MSG_DATATYPE, 0x0008),
            (MSG_FILL_VALUE, 0x0020),
            (MSG_FILTER_PIPELINE, 0x0800),
            (MSG_ATTRIBUTE, 0x1000),
        ];
        for (kind, flags) in kinds {
            for (other, _) in kinds {
                assert_eq!(index(flags).tracks_message_type(other), other == kind);
            }
            assert!(index(0x182A).tracks_message_type(kind));
        }
        assert!(index(0x0020).tracks_message_type(MSG_FILL_VALUE_OLD));
        // 0x1F, every kind in the bits 0.12.1 used (0 to 4), holds dataspaces (bit 1) and
        // datatypes (bit 3) only.
        assert!(index(0x001F).tracks_message_type(MSG_DATASPACE));
        assert!(index(0x001F).tracks_message_type(MSG_DATATYPE));
        for kind in [MSG_FILL_VALUE, MSG_FILTER_PIPELINE, MSG_ATTRIBUTE] {
            assert!(!index(0x001F).tracks_message_type(kind));
        }
    }

    #[test]
    fn parses_record_list_heap_record() {
        let mut data = vec![0u8; 32];
        let mut list = Vec::new();
        list.extend_from_slice(b"SMLI");
        list.push(0);
        list.extend_from_slice(&0x1122_3344u32.to_le_bytes());
        list.extend_from_slice(&2u32.to_le_bytes());
        list.extend_from_slice(&[8, 7, 6, 5, 4, 3, 2, 1]);
        let checksum = jenkins_lookup3(&list);
        list.extend_from_slice(&checksum.to_le_bytes());
        data.extend_from_slice(&list);

        let storage = BytesStorage::new(data);
        let records = parse_record_list(&storage, 32, 1, 8).unwrap();
        match &records[0] {
            SharedMessageRecord::Heap {
                hash,
                reference_count,
                heap_id,
            } => {
                assert_eq!(*hash, 0x1122_3344);
                assert_eq!(*reference_count, 2);
                assert_eq!(heap_id, &[8, 7, 6, 5, 4, 3, 2, 1]);
            }
            other => panic!("expected heap record, got {:?}", other),
        }
    }
}
