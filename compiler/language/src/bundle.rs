//! Bundles: one versioned, checksummed file holding a checked project, which `mocu run`
//! loads without the sources.
//!
//! Format: one header line, then the JSON body.
//! ```text
//! MOCU-BUNDLE v1 mocu 0.1.0 crc32=1a2b3c4d len=12345
//! {"profile":…,"schema":…,"layouts":[…]}
//! ```
//! `crc32` (IEEE) and `len` cover the body. A bundle from another format or another mocu
//! version is refused: the typed program is not a stable interface between versions.

use crate::profile::Profile;
use crate::program::Program;
use crate::schema::Schema;
use serde::{Deserialize, Serialize};
use std::fmt;

pub const MAGIC: &str = "MOCU-BUNDLE";
pub const FORMAT: u32 = 1;
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// A checked project.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Bundle {
    /// `None` when built from a lone layout file.
    pub profile: Option<Profile>,
    pub schema: Schema,
    pub layouts: Vec<Layout>,
    /// The text files the profile's modules name (a script module's `file`, the map's
    /// `overlays`), by the path written in the profile: a bundle runs without the sources
    /// (`mocu build` fills it; `mocu run` hands them to the modules).
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub files: std::collections::BTreeMap<String, String>,
}

/// One checked layout file, with everything it uses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    /// The layout's path as written in the profile (or given on the command line).
    pub path: String,
    pub program: Program,
}

#[derive(Debug, PartialEq)]
pub enum BundleError {
    NotABundle,
    /// Built by another format or version.
    Version {
        format: String,
        version: String,
    },
    Corrupt(String),
    Malformed(String),
}

impl fmt::Display for BundleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BundleError::NotABundle => write!(f, "not a mocu bundle (no `{MAGIC}` header)"),
            BundleError::Version { format, version } => write!(
                f,
                "this bundle was built by mocu {version} (bundle format {format}); this is mocu {VERSION} (bundle format v{FORMAT}): rebuild it with `mocu build`"
            ),
            BundleError::Corrupt(why) => {
                write!(f, "the bundle is corrupt ({why}): rebuild it with `mocu build`")
            }
            BundleError::Malformed(why) => write!(f, "the bundle cannot be read: {why}"),
        }
    }
}

impl std::error::Error for BundleError {}

/// Whether bytes start like a bundle (to tell a bundle from a layout or profile).
pub fn is_bundle(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC.as_bytes())
}

pub fn write(bundle: &Bundle) -> Vec<u8> {
    let body = serde_json::to_vec(bundle).unwrap_or_default();
    let mut out =
        format!("{MAGIC} v{FORMAT} mocu {VERSION} crc32={:08x} len={}\n", crc32(&body), body.len())
            .into_bytes();
    out.extend_from_slice(&body);
    out
}

pub fn read(bytes: &[u8]) -> Result<Bundle, BundleError> {
    if !is_bundle(bytes) {
        return Err(BundleError::NotABundle);
    }
    let nl = bytes
        .iter()
        .position(|&b| b == b'\n')
        .ok_or_else(|| BundleError::Corrupt("no header line".into()))?;
    let header = std::str::from_utf8(&bytes[..nl])
        .map_err(|_| BundleError::Corrupt("header is not text".into()))?;
    let body = &bytes[nl + 1..];
    let fields: Vec<&str> = header.split(' ').collect();
    let [_, format, tool, version, crc, len] = fields.as_slice() else {
        return Err(BundleError::Corrupt(format!("unexpected header `{header}`")));
    };
    if *tool != "mocu" || *format != format!("v{FORMAT}") || *version != VERSION {
        return Err(BundleError::Version {
            format: format.to_string(),
            version: version.to_string(),
        });
    }
    let want_len: usize = len
        .strip_prefix("len=")
        .and_then(|l| l.parse().ok())
        .ok_or_else(|| BundleError::Corrupt("bad length".into()))?;
    if want_len != body.len() {
        return Err(BundleError::Corrupt(format!(
            "{} bytes of body, header says {want_len}",
            body.len()
        )));
    }
    let want_crc = crc
        .strip_prefix("crc32=")
        .and_then(|c| u32::from_str_radix(c, 16).ok())
        .ok_or_else(|| BundleError::Corrupt("bad checksum field".into()))?;
    if crc32(body) != want_crc {
        return Err(BundleError::Corrupt("checksum mismatch".into()));
    }
    let bundle = serde_json::from_slice(body).map_err(|e| BundleError::Malformed(e.to_string()));
    crate::program::Lets::end_reading();
    bundle
}

/// CRC-32 (IEEE 802.3, reflected, as zlib).
pub fn crc32(data: &[u8]) -> u32 {
    static TABLE: std::sync::OnceLock<[u32; 256]> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        let mut t = [0u32; 256];
        for (i, slot) in t.iter_mut().enumerate() {
            let mut c = i as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            }
            *slot = c;
        }
        t
    });
    !data.iter().fold(!0u32, |c, &b| table[((c ^ b as u32) & 0xff) as usize] ^ (c >> 8))
}
