//! A recording is outside input: every length, offset and size it states is checked
//! against what the file holds before anything is allocated or read for it
//! (docs/recording.md, "Damaged recordings").

use crate::file::ReplayError;

/// The most a chunk may say it decompresses to, per byte it holds. LZ4's format cannot
/// exceed 255:1; zstd can, for data of one repeated byte, so the bound is looser. A chunk
/// that claims more is refused rather than allocated.
pub const MAX_EXPANSION: u64 = 1024;

/// Slack on top of [`MAX_EXPANSION`] for tiny chunks (headers, frame overhead).
const SLACK: u64 = 64 * 1024;

/// `offset..offset + length` of the `record` lies inside a file of `size` bytes.
pub fn span(record: &'static str, offset: u64, length: u64, size: u64) -> Result<(), ReplayError> {
    match offset.checked_add(length) {
        Some(end) if end <= size => Ok(()),
        _ => Err(ReplayError::Damaged {
            record,
            offset,
            reason: format!("says it is {length} bytes, past the end of the {size}-byte file"),
        }),
    }
}

/// A chunk of `compressed` bytes that says it holds `uncompressed`: plausible, and
/// `compressed` itself within the `available` bytes.
pub fn chunk(
    offset: u64,
    compression: &str,
    compressed: u64,
    uncompressed: u64,
    available: u64,
) -> Result<(), ReplayError> {
    let damaged = |reason: String| ReplayError::Damaged { record: "chunk", offset, reason };
    if compressed > available {
        return Err(damaged(format!(
            "says it holds {compressed} compressed bytes; only {available} remain"
        )));
    }
    let most = if compression.is_empty() {
        compressed
    } else {
        compressed.saturating_mul(MAX_EXPANSION).saturating_add(SLACK)
    };
    if uncompressed > most {
        return Err(damaged(format!(
            "says {compressed} bytes ({}) decompress to {uncompressed}: more than {most}",
            if compression.is_empty() { "uncompressed" } else { compression }
        )));
    }
    Ok(())
}

/// Every chunk, message-index, metadata and attachment index of the summary checked
/// against the file's `size`.
pub fn summary(s: &mcap::Summary, size: u64) -> Result<(), ReplayError> {
    for c in &s.chunk_indexes {
        span("chunk", c.chunk_start_offset, c.chunk_length, size)?;
        chunk(
            c.chunk_start_offset,
            &c.compression,
            c.compressed_size,
            c.uncompressed_size,
            c.chunk_length,
        )?;
        for &o in c.message_index_offsets.values() {
            span("message index", o, 0, size)?;
        }
    }
    for m in &s.metadata_indexes {
        span("metadata", m.offset, m.length, size)?;
    }
    for a in &s.attachment_indexes {
        span("attachment", a.offset, a.length, size)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_length_past_the_end_of_the_file_is_refused_naming_the_record_and_its_offset() {
        let e = span("metadata", 100, 1 << 40, 4096).unwrap_err();
        assert_eq!(
            e.to_string(),
            "damaged recording: the metadata at byte 100 says it is 1099511627776 bytes, \
             past the end of the 4096-byte file"
        );
        assert!(span("attachment", u64::MAX, 2, 4096).is_err(), "offset + length overflows");
        assert!(span("chunk", 96, 4000, 4096).is_ok());
    }

    #[test]
    fn a_chunk_that_claims_more_than_it_can_decompress_to_is_refused() {
        assert!(chunk(8, "lz4", 1000, 1000 * MAX_EXPANSION, 1000).is_ok());
        assert!(chunk(8, "zstd", 1000, 1 << 63, 1000).is_err());
        assert!(chunk(8, "", 1000, 1001, 1000).is_err(), "uncompressed sizes must agree");
        let e = chunk(8, "lz4", 5000, 10, 1000).unwrap_err();
        assert!(matches!(e, ReplayError::Damaged { record: "chunk", offset: 8, .. }), "{e}");
    }
}
