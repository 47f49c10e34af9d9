//! Reading a recording: the `mocu` metadata, the bundle, and messages by time through the
//! chunk index. A file a killed recorder left (no summary) is read linearly, once, up to
//! its last complete chunk, and kept in memory.

use mcap::records::Record;
use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Arc;

/// Why a recording cannot be replayed.
#[derive(Debug)]
pub enum ReplayError {
    Io(String),
    /// Not an MCAP file, or not one `mocu run --record` wrote.
    Format(String),
    /// A record that states more than the file holds (a length, offset or size): the
    /// file is damaged or crafted, and nothing is allocated for it.
    Damaged {
        record: &'static str,
        offset: u64,
        reason: String,
    },
}

impl std::fmt::Display for ReplayError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReplayError::Io(e) | ReplayError::Format(e) => f.write_str(e),
            ReplayError::Damaged { record, offset, reason } => {
                write!(f, "damaged recording: the {record} at byte {offset} {reason}")
            }
        }
    }
}

impl std::error::Error for ReplayError {}

fn format_error(e: mcap::McapError) -> ReplayError {
    ReplayError::Format(e.to_string())
}

/// The `mocu` metadata record (docs/recording.md, "The file").
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Meta {
    /// Every key as written.
    pub fields: BTreeMap<String, String>,
    /// The DataServer's wall clock when recording started (ns since the Unix epoch).
    pub start_ns: Option<u64>,
}

impl Meta {
    pub fn get(&self, key: &str) -> Option<&str> {
        self.fields.get(key).map(String::as_str)
    }
}

/// One message, owned: its time, its number and its topic.
#[derive(Clone, Debug, PartialEq)]
pub struct RawMessage {
    pub log_time: u64,
    pub sequence: u32,
    pub topic: Arc<str>,
    pub data: Vec<u8>,
}

/// An open recording.
pub struct Recording {
    file: File,
    /// The file's length: what every length it states is bounded by.
    size: u64,
    summary: Option<mcap::Summary>,
    /// Without a summary: every message, in (log time, sequence) order.
    linear: Vec<RawMessage>,
    topics: HashMap<u16, Arc<str>>,
    meta: Meta,
    bundle: Option<Vec<u8>>,
    span: (u64, u64),
}

impl Recording {
    pub fn open(path: &Path) -> Result<Recording, ReplayError> {
        let io = |e: std::io::Error| ReplayError::Io(format!("{}: {e}", path.display()));
        let mut file = File::open(path).map_err(io)?;
        let size = file.metadata().map_err(io)?.len();
        // A summary that states more than the file holds is not used: the file is read
        // linearly instead, as one a killed recorder left.
        let summary = read_summary(&mut file, size)
            .ok()
            .flatten()
            .filter(|s| crate::bounds::summary(s, size).is_ok());
        let mut r = Recording {
            file,
            size,
            summary,
            linear: Vec::new(),
            topics: HashMap::new(),
            meta: Meta::default(),
            bundle: None,
            span: (0, 0),
        };
        match r.summary.clone() {
            Some(s) => r.index_from_summary(&s)?,
            None => r.read_linearly(path)?,
        }
        if r.meta.fields.is_empty() {
            return Err(ReplayError::Format(format!(
                "{}: no `mocu` metadata: not a recording of `mocu run --record`",
                path.display()
            )));
        }
        Ok(r)
    }

    pub fn meta(&self) -> &Meta {
        &self.meta
    }

    /// The bundle the run started with (`bundle.mocub`), if it was attached.
    pub fn bundle(&self) -> Option<&[u8]> {
        self.bundle.as_deref()
    }

    /// The log times of the first and the last message.
    pub fn span(&self) -> (u64, u64) {
        self.span
    }

    /// The topics that start with `prefix`, in order.
    pub fn topics_starting(&self, prefix: &str) -> Vec<Arc<str>> {
        let mut t: Vec<Arc<str>> =
            self.topics.values().filter(|t| t.starts_with(prefix)).cloned().collect();
        t.sort();
        t.dedup();
        t
    }

    /// Whether the file had its summary (else it was read linearly: a killed recorder).
    pub fn indexed(&self) -> bool {
        self.summary.is_some()
    }

    /// The messages of `topics` with `from <= log_time <= to`, in (log time, sequence)
    /// order; through the chunk index, reading only the chunks that overlap.
    pub fn messages(
        &mut self,
        from: u64,
        to: u64,
        topics: &[&str],
    ) -> Result<Vec<RawMessage>, ReplayError> {
        if self.summary.is_none() {
            let lo = self.linear.partition_point(|m| m.log_time < from);
            let hi = self.linear.partition_point(|m| m.log_time <= to);
            return Ok(self.linear[lo..hi]
                .iter()
                .filter(|m| topics.contains(&&*m.topic))
                .cloned()
                .collect());
        }
        let (from, to) = (from.max(self.span.0), to.min(self.span.1));
        let channels = self.channels(topics);
        let mut out = Vec::new();
        for c in self.chunks_with(&channels) {
            if c.message_start_time > to || c.message_end_time < from {
                continue;
            }
            let data = self.chunk_data(&c)?;
            for rec in crate::chunk::records(&data) {
                if let Record::Message { header, data } = rec
                    && channels.contains(&header.channel_id)
                    && (from..=to).contains(&header.log_time)
                    && (c.message_start_time..=c.message_end_time).contains(&header.log_time)
                {
                    out.push(self.message(&header, &data));
                }
            }
        }
        out.sort_by_key(|m| (m.log_time, m.sequence));
        Ok(out)
    }

    /// The last message of `topic` with `log_time <= at`.
    pub fn last_at_or_before(
        &mut self,
        topic: &str,
        at: u64,
    ) -> Result<Option<RawMessage>, ReplayError> {
        if self.summary.is_none() {
            let hi = self.linear.partition_point(|m| m.log_time <= at);
            return Ok(self.linear[..hi].iter().rev().find(|m| &*m.topic == topic).cloned());
        }
        let at = at.min(self.span.1);
        let channels = self.channels(&[topic]);
        let mut chunks: Vec<mcap::records::ChunkIndex> = self
            .chunks_with(&channels)
            .into_iter()
            .filter(|c| c.message_start_time <= at)
            .collect();
        chunks.sort_by_key(|c| std::cmp::Reverse(c.message_end_time));
        let mut best: Option<RawMessage> = None;
        for c in chunks {
            // The chunks left end before the best found so far.
            if best.as_ref().is_some_and(|b| b.log_time > c.message_end_time) {
                break;
            }
            let data = self.chunk_data(&c)?;
            for rec in crate::chunk::records(&data) {
                if let Record::Message { header, data } = rec
                    && channels.contains(&header.channel_id)
                    && header.log_time <= at
                    && header.log_time >= self.span.0
                    && (c.message_start_time..=c.message_end_time).contains(&header.log_time)
                    && best.as_ref().is_none_or(|b| {
                        (header.log_time, header.sequence) > (b.log_time, b.sequence)
                    })
                {
                    best = Some(self.message(&header, &data));
                }
            }
        }
        Ok(best)
    }

    /// The log time of the first message after `t` (a lower bound, read from the chunk
    /// index without reading chunks); `u64::MAX` when there is none. Replay skips the gap.
    pub fn next_after(&self, t: u64) -> u64 {
        if t >= self.span.1 {
            return u64::MAX;
        }
        let Some(s) = &self.summary else {
            let i = self.linear.partition_point(|m| m.log_time <= t);
            return self.linear.get(i).map_or(u64::MAX, |m| m.log_time);
        };
        let after = t.saturating_add(1);
        s.chunk_indexes
            .iter()
            .filter(|c| c.message_end_time > t)
            .map(|c| c.message_start_time.max(after))
            .min()
            .unwrap_or(u64::MAX)
    }

    /// The channels of `topics`.
    fn channels(&self, topics: &[&str]) -> HashSet<u16> {
        self.topics.iter().filter(|(_, t)| topics.contains(&&***t)).map(|(id, _)| *id).collect()
    }

    /// The summary's chunks that may hold messages on `channels` (by their message
    /// indexes; every chunk where the writer wrote none), in file order.
    fn chunks_with(&self, channels: &HashSet<u16>) -> Vec<mcap::records::ChunkIndex> {
        let Some(s) = &self.summary else { return Vec::new() };
        s.chunk_indexes
            .iter()
            .filter(|c| {
                c.message_index_offsets.is_empty()
                    || c.message_index_offsets.keys().any(|id| channels.contains(id))
            })
            .cloned()
            .collect()
    }

    /// A chunk's records, decompressed.
    fn chunk_data(&mut self, c: &mcap::records::ChunkIndex) -> Result<Vec<u8>, ReplayError> {
        let damaged = |reason: String| ReplayError::Damaged {
            record: "chunk",
            offset: c.chunk_start_offset,
            reason,
        };
        let at = c.compressed_data_offset().map_err(|e| damaged(e.to_string()))?;
        let compressed = self.read_at("chunk", at, c.compressed_size)?;
        crate::chunk::decompress(
            c.chunk_start_offset,
            &c.compression,
            &compressed,
            c.uncompressed_size,
        )
    }

    fn message(&self, header: &mcap::records::MessageHeader, data: &[u8]) -> RawMessage {
        RawMessage {
            log_time: header.log_time,
            sequence: header.sequence,
            topic: self.topics.get(&header.channel_id).cloned().unwrap_or_else(|| "".into()),
            data: data.to_vec(),
        }
    }

    fn read_at(
        &mut self,
        record: &'static str,
        offset: u64,
        length: u64,
    ) -> Result<Vec<u8>, ReplayError> {
        crate::bounds::span(record, offset, length, self.size)?;
        let mut buf = vec![0; length as usize];
        self.file
            .seek(SeekFrom::Start(offset))
            .and_then(|_| self.file.read_exact(&mut buf))
            .map_err(|e| ReplayError::Io(e.to_string()))?;
        Ok(buf)
    }

    fn index_from_summary(&mut self, s: &mcap::Summary) -> Result<(), ReplayError> {
        self.topics = s.channels.iter().map(|(id, c)| (*id, Arc::from(c.topic.as_str()))).collect();
        for m in &s.metadata_indexes {
            let buf = self.read_at("metadata", m.offset, m.length)?;
            if let Some(Ok(Record::Metadata(meta))) =
                mcap::read::LinearReader::sans_magic(&buf).next()
            {
                self.take_meta(&meta);
            }
        }
        for a in &s.attachment_indexes {
            if a.name == "bundle.mocub" {
                let buf = self.read_at("attachment", a.offset, a.length)?;
                if let Some(Ok(Record::Attachment { data, .. })) =
                    mcap::read::LinearReader::sans_magic(&buf).next()
                {
                    self.bundle = Some(data.into_owned());
                }
            }
        }
        // What the chunk indexes and the statistics both say: one damaged field of either
        // cannot stretch the trial.
        let lo = s.chunk_indexes.iter().map(|c| c.message_start_time).min().unwrap_or(0);
        let hi = s.chunk_indexes.iter().map(|c| c.message_end_time).max().unwrap_or(0);
        let (lo, hi) = match &s.stats {
            Some(st) => (lo.max(st.message_start_time), hi.min(st.message_end_time)),
            None => (lo, hi),
        };
        let (first, last) = crate::times::window(self.meta.start_ns, lo);
        self.span = (lo.max(first), hi.min(last));
        Ok(())
    }

    /// A file without a summary: every record in order, up to the first that cannot be
    /// read (a torn chunk).
    fn read_linearly(&mut self, path: &Path) -> Result<(), ReplayError> {
        let bytes = std::fs::read(path).map_err(|e| ReplayError::Io(e.to_string()))?;
        let lenient = mcap::read::Options::IgnoreEndMagic.into();
        let reader =
            mcap::read::LinearReader::new_with_options(&bytes, lenient).map_err(format_error)?;
        let mut records: Vec<Record<'static>> = Vec::new();
        for rec in reader {
            let Ok(rec) = rec else { break };
            records.push(rec.into_owned());
        }
        for rec in records {
            self.take_record(rec);
        }
        let lo = self.linear.iter().map(|m| m.log_time).min().unwrap_or(0);
        let (first, last) = crate::times::window(self.meta.start_ns, lo);
        self.linear.retain(|m| (first..=last).contains(&m.log_time));
        self.linear.sort_by_key(|m| (m.log_time, m.sequence));
        self.span = match (self.linear.first(), self.linear.last()) {
            (Some(a), Some(b)) => (a.log_time, b.log_time),
            _ => (0, 0),
        };
        Ok(())
    }

    fn take_record(&mut self, rec: Record<'_>) {
        match rec {
            Record::Channel(c) => {
                self.topics.insert(c.id, Arc::from(c.topic.as_str()));
            }
            Record::Metadata(m) => self.take_meta(&m),
            Record::Attachment { header, data, .. } if header.name == "bundle.mocub" => {
                self.bundle = Some(data.into_owned());
            }
            Record::Chunk { header, data } => {
                // Offsets are not known here: 0 names none.
                let Ok(inner) = crate::chunk::decompress(
                    0,
                    &header.compression,
                    &data,
                    header.uncompressed_size,
                ) else {
                    return;
                };
                let stated = header.message_start_time..=header.message_end_time;
                for r in crate::chunk::records(&inner) {
                    // A message outside its chunk's stated times is damaged: dropped.
                    if let Record::Message { header: m, .. } = &r
                        && !stated.contains(&m.log_time)
                    {
                        continue;
                    }
                    self.take_record(r);
                }
            }
            Record::Message { header, data } => self.linear.push(RawMessage {
                log_time: header.log_time,
                sequence: header.sequence,
                topic: self.topics.get(&header.channel_id).cloned().unwrap_or_else(|| "".into()),
                data: data.into_owned(),
            }),
            _ => {}
        }
    }

    fn take_meta(&mut self, m: &mcap::records::Metadata) {
        if m.name == "mocu" {
            self.meta.fields = m.metadata.clone().into_iter().collect();
            self.meta.start_ns = self.meta.get("start_ns").and_then(|s| s.parse().ok());
        }
    }
}

fn read_summary(file: &mut File, size: u64) -> Result<Option<mcap::Summary>, ReplayError> {
    let io = |e: std::io::Error| ReplayError::Io(e.to_string());
    let mut reader =
        SummaryReader::new_with_options(SummaryReaderOptions::default().with_file_size(size));
    while let Some(event) = reader.next_event() {
        match event.map_err(format_error)? {
            SummaryReadEvent::ReadRequest(n) => {
                let read = file.read(reader.insert(n)).map_err(io)?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = file.seek(to).map_err(io)?;
                reader.notify_seeked(pos);
            }
        }
    }
    Ok(reader.finish())
}
