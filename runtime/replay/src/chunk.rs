//! A chunk's records: its data decompressed (none, LZ4, or zstd with the pure-Rust
//! `ruzstd`) into exactly the size it states, that size first checked as plausible for the
//! bytes it holds ([`crate::bounds::chunk`]), and the records inside read by a reader that
//! bounds each record's length by what the chunk holds.

use crate::file::ReplayError;
use mcap::records::Record;
use std::io::Read;

/// The decompressed records of the chunk at `offset`.
pub fn decompress(
    offset: u64,
    compression: &str,
    compressed: &[u8],
    uncompressed_size: u64,
) -> Result<Vec<u8>, ReplayError> {
    let len = compressed.len() as u64;
    crate::bounds::chunk(offset, compression, len, uncompressed_size, len)?;
    let damaged = |reason: String| ReplayError::Damaged { record: "chunk", offset, reason };
    let mut out = Vec::with_capacity(uncompressed_size as usize);
    // One byte more than stated, to tell a chunk that holds more than it says.
    let limit = uncompressed_size + 1;
    let read = match compression {
        "" => return Ok(compressed.to_vec()),
        "lz4" => lz4::Decoder::new(compressed).and_then(|d| d.take(limit).read_to_end(&mut out)),
        "zstd" => ruzstd::decoding::StreamingDecoder::new(compressed)
            .map_err(|e| std::io::Error::other(e.to_string()))
            .and_then(|d| d.take(limit).read_to_end(&mut out)),
        other => {
            return Err(ReplayError::Format(format!(
                "the chunk at byte {offset} is compressed with `{other}`: \
                 replay reads chunks uncompressed, LZ4 or zstd"
            )));
        }
    };
    read.map_err(|e| damaged(format!("does not decompress ({compression}): {e}")))?;
    if out.len() as u64 != uncompressed_size {
        return Err(damaged(format!(
            "decompresses to {}{} bytes, not the {uncompressed_size} it states",
            if out.len() as u64 > uncompressed_size { "more than " } else { "" },
            out.len().min(uncompressed_size as usize)
        )));
    }
    Ok(out)
}

/// The records in decompressed chunk data, up to the first that cannot be read.
pub fn records(data: &[u8]) -> impl Iterator<Item = Record<'_>> {
    mcap::read::LinearReader::sans_magic(data).map_while(Result::ok)
}
