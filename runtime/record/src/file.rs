//! The MCAP file: chunked (LZ4) and indexed, with the channels of docs/recording.md. Each
//! channel's `log_time` is held from going back; a chunk is closed and the file flushed at
//! least once a second, so a killed recording loses at most that.

use crate::{schemas, values};
use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions, Writer};
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

/// Chunks close at this size (uncompressed) or when the file is flushed.
const CHUNK: u64 = 1 << 20;

pub(crate) struct Out {
    w: Writer<BufWriter<File>>,
    pub object: u16,
    pub property: u16,
    pub values: u16,
    pub snapshot: u16,
    pub calls: u16,
    pub events: u16,
    pub layout: u16,
    video_schema: u16,
    image_schema: u16,
    raw_image_schema: u16,
    location_schema: u16,
    /// Channels made on demand (`/video/…`, `/image/…`, `/camera/…`, `/location/…`) by topic.
    dynamic: HashMap<String, u16>,
    /// The last `log_time` written on each channel (by id).
    last: Vec<u64>,
    /// Bytes handed to the writer since the file was opened.
    pub bytes: u64,
    pub messages: u64,
}

#[derive(Clone, Copy)]
pub(crate) enum Dynamic {
    Video,
    Image,
    /// `foxglove_msgs/msg/RawImage`, CDR.
    RawImage,
    Location,
}

fn err(e: mcap::McapError) -> String {
    e.to_string()
}

impl Out {
    pub fn create(path: &Path) -> Result<Out, String> {
        let f = File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let opts = WriteOptions::new()
            .profile("mocu")
            .library(format!("mocu-record {}", env!("CARGO_PKG_VERSION")))
            // LZ4: about a fifth of the recorder's CPU in a busy trial (docs/recording.md,
            // "Cost"), but a simulator camera's raw frames shrink 30 times.
            .compression(Some(Compression::Lz4))
            .chunk_size(Some(CHUNK));
        let mut w = opts.create(BufWriter::with_capacity(1 << 16, f)).map_err(err)?;
        let channel = |w: &mut Writer<_>, topic: &str, (name, schema): (&str, &str)| {
            let s = w.add_schema(name, "jsonschema", schema.as_bytes())?;
            w.add_channel(s, topic, "json", &BTreeMap::new())
        };
        let object = channel(&mut w, "/world/object", schemas::OBJECT).map_err(err)?;
        let property =
            channel(&mut w, "/world/property", ("mocu.PropertyChange", &schemas::property()))
                .map_err(err)?;
        let values_schema =
            w.add_schema(values::SCHEMA_NAME, "ros2msg", values::SCHEMA.as_bytes()).map_err(err)?;
        let values =
            w.add_channel(values_schema, "/world/values", "cdr", &BTreeMap::new()).map_err(err)?;
        let snapshot =
            channel(&mut w, "/world/snapshot", ("mocu.WorldSnapshot", &schemas::snapshot()))
                .map_err(err)?;
        let calls = channel(&mut w, "/calls", ("mocu.Call", &schemas::call())).map_err(err)?;
        let events = channel(&mut w, "/events", schemas::EVENT).map_err(err)?;
        let layout = channel(&mut w, "/layout", schemas::LAYOUT).map_err(err)?;
        let video_schema = w
            .add_schema(
                schemas::COMPRESSED_VIDEO.0,
                "ros2msg",
                schemas::COMPRESSED_VIDEO.1.as_bytes(),
            )
            .map_err(err)?;
        let image_schema = w
            .add_schema(
                schemas::COMPRESSED_IMAGE.0,
                "ros2msg",
                schemas::COMPRESSED_IMAGE.1.as_bytes(),
            )
            .map_err(err)?;
        let raw_image_schema = w
            .add_schema(schemas::RAW_IMAGE.0, "ros2msg", schemas::RAW_IMAGE.1.as_bytes())
            .map_err(err)?;
        let location_schema = w
            .add_schema("foxglove.LocationFix", "jsonschema", schemas::location_fix().as_bytes())
            .map_err(err)?;
        Ok(Out {
            w,
            object,
            property,
            values,
            snapshot,
            calls,
            events,
            layout,
            video_schema,
            image_schema,
            raw_image_schema,
            location_schema,
            dynamic: HashMap::new(),
            last: Vec::new(),
            bytes: 0,
            messages: 0,
        })
    }

    pub fn metadata(&mut self, name: &str, fields: BTreeMap<String, String>) -> Result<(), String> {
        self.w
            .write_metadata(&mcap::records::Metadata { name: name.into(), metadata: fields })
            .map_err(err)
    }

    pub fn attach(
        &mut self,
        name: &str,
        media_type: &str,
        time: u64,
        data: &[u8],
    ) -> Result<(), String> {
        let a = mcap::Attachment {
            log_time: time,
            create_time: time,
            name: name.into(),
            media_type: media_type.into(),
            data: std::borrow::Cow::Borrowed(data),
        };
        self.w.attach(&a).map_err(err)
    }

    /// The channel of a camera's or an object's `topic`, made the first time.
    pub fn dynamic(&mut self, kind: Dynamic, topic: &str) -> Result<u16, String> {
        if let Some(&id) = self.dynamic.get(topic) {
            return Ok(id);
        }
        let (schema, encoding) = match kind {
            Dynamic::Video => (self.video_schema, "cdr"),
            Dynamic::Image => (self.image_schema, "cdr"),
            Dynamic::RawImage => (self.raw_image_schema, "cdr"),
            Dynamic::Location => (self.location_schema, "json"),
        };
        let id = self.w.add_channel(schema, topic, encoding, &BTreeMap::new()).map_err(err)?;
        self.dynamic.insert(topic.to_string(), id);
        Ok(id)
    }

    /// Writes one message; returns the `log_time` it was written with (never before the
    /// channel's previous one).
    pub fn write(
        &mut self,
        channel: u16,
        sequence: u64,
        time: u64,
        data: &[u8],
    ) -> Result<u64, String> {
        let c = channel as usize;
        if self.last.len() <= c {
            self.last.resize(c + 1, 0);
        }
        let t = time.max(self.last[c]);
        self.last[c] = t;
        let header = MessageHeader {
            channel_id: channel,
            sequence: sequence as u32,
            log_time: t,
            publish_time: t,
        };
        self.w.write_to_known_channel(&header, data).map_err(err)?;
        self.bytes += data.len() as u64;
        self.messages += 1;
        Ok(t)
    }

    /// Closes the current chunk and flushes the file: what was written survives a kill.
    pub fn flush(&mut self) -> Result<(), String> {
        self.w.flush().map_err(err)
    }

    /// Writes the summary (indexes, statistics) and the footer.
    pub fn finish(mut self) -> Result<(), String> {
        self.w.finish().map_err(err)?;
        Ok(())
    }
}
