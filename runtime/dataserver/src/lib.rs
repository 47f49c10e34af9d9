//! The DataServer: Mocu's shared-world model (MOCU 3 paper §4).
//!
//! An object tree under one root; typed properties with metadata; subscriptions to an
//! object's properties or children with initial values, coalescing and delta isolation;
//! methods with call feedback, queued and delayed calls; streams through listener objects;
//! dotted-path subscriptions that follow system discovery.
//!
//! Architecture invariant: this crate does no I/O and knows nothing of the compiler, the
//! renderer, input devices or file watching. Writes run on the caller's thread;
//! notification work runs on the DataServer's own workers.

#![forbid(unsafe_code)]

mod call;
mod clock;
mod error;
mod executor;
mod feed;
mod hash;
mod meta;
mod method;
mod notification;
mod object;
mod path;
mod props;
mod server;
mod snapshot;
mod stream;
mod subscription;
mod timer;

pub use call::{Call, Responder};
pub use clock::{Clock, ManualClock, SystemClock};
pub use error::{DsError, ObjRef};
pub use executor::{Executor, Stats};
pub use feed::{Change, ChangeFeed, FeedWaker, NumKind, Numeric, Stamped};
pub use meta::{ObjectInfo, PropMeta};
pub use method::{CallMode, CallOptions, CallOutcome, MethodSpec, ParamSpec, WRITE_AT_OWNER};
pub use mocu_value::{Guid, PropName, Value, ValueKind};
pub use notification::{Kind, Notification, Subject};
pub use path::{DottedPath, PathEvent, PathWatch};
pub use server::{Config, DataServer};
pub use snapshot::Snapshot;
pub use stream::{LISTENER_TYPE, Overflow, RECEIVER_TYPE};
pub use subscription::{SubscriptionId, Topic};
