//! Replay of a trial recording (`mocu replay`, docs/recording.md): the world-model changes
//! of an MCAP file applied to a fresh DataServer in their recorded order, each at its
//! recorded trial time on a [`ManualClock`](mocu_dataserver::ManualClock) the replay moves.
//!
//! - [`Recording`] reads the file: its `mocu` metadata, the bundle it was made with, and
//!   messages by time through MCAP's chunk index (linearly when a killed recorder left no
//!   summary).
//! - [`World`] applies `/world/object` and `/world/property` messages and `/world/snapshot`
//!   keyframes, mapping the recording's GUIDs to the new server's. The recorded
//!   `root.display` is left out: the layout being replayed draws its own.
//! - Frames of cameras that send pixels (`/camera/…`) are sent again on the replayed
//!   camera's listener at their times, so video windows show them as they showed live.
//! - [`Player`] is the timeline: `seek` (the last keyframe before the time, then the changes
//!   after it), `advance_to` (each change at its own time, timers firing in order between
//!   them, `DataServer::advance_settled`), so the same recording gives the same world at the
//!   same trial time, run after run.
//!
//! Architecture invariant: replay knows nothing of layouts or displays; it writes the
//! world model, as a protocol module would.

#![forbid(unsafe_code)]

mod bounds;
mod chunk;
mod file;
mod message;
mod player;
mod times;
mod value;
mod world;

pub use file::{Meta, RawMessage, Recording, ReplayError};
pub use message::{
    Frame, ObjectChange, PropertyChange, Snapshot, SnapshotObject, Unit, ValueEntry, values,
};
pub use player::Player;
pub use times::{BEFORE_START_NS, MAX_TRIAL_NS};
pub use world::World;

/// Topics replay reads.
pub mod topics {
    pub const OBJECT: &str = "/world/object";
    pub const PROPERTY: &str = "/world/property";
    pub const SNAPSHOT: &str = "/world/snapshot";
    pub const VALUES: &str = "/world/values";
    /// Frames of cameras that send pixels: `/camera/<camera path>`.
    pub const CAMERA_PREFIX: &str = "/camera/";
    /// A network camera's units as received: H.264 (`/video/…`) and JPEG (`/image/…`).
    pub const VIDEO_PREFIX: &str = "/video/";
    pub const IMAGE_PREFIX: &str = "/image/";
}
