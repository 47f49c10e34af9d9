//! What each module kind of `mocu run` accepts as settings (`[modules.NAME]` tables of a
//! profile): the declaration the compiler checks profiles against, without depending on the
//! runtime crates. The runtime reads the same keys (`mocu-sim`, `mocu-mavlink`, `mocu-video`,
//! `mocu-input`, `mocu-widgets`, …); a test of the `mocu` binary starts every kind with every key declared here.
//! docs/language.md, "Profiles", lists them (and a test keeps that list complete).

/// The type of a setting's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SettingType {
    Int,
    Number,
    Bool,
    String,
    /// An array of strings.
    Names,
}

impl SettingType {
    pub fn describe(self) -> &'static str {
        match self {
            SettingType::Int => "a whole number",
            SettingType::Number => "a number",
            SettingType::Bool => "true or false",
            SettingType::String => "a string",
            SettingType::Names => "a list of names, e.g. [\"usv1\", \"uav1\"]",
        }
    }

    /// Whether a TOML value has this type.
    pub fn accepts(self, v: &toml::Value) -> bool {
        match (self, v) {
            (SettingType::Int, toml::Value::Integer(_)) => true,
            (SettingType::Number, toml::Value::Integer(_) | toml::Value::Float(_)) => true,
            (SettingType::Bool, toml::Value::Boolean(_)) => true,
            (SettingType::String, toml::Value::String(_)) => true,
            (SettingType::Names, toml::Value::Array(a)) => a.iter().all(|x| x.is_str()),
            _ => false,
        }
    }
}

/// One setting a module kind accepts.
#[derive(Clone, Copy, Debug)]
pub struct Setting {
    pub name: &'static str,
    pub ty: SettingType,
    /// The value used when the key is left out, as text.
    pub default: &'static str,
    pub description: &'static str,
}

/// A module kind and its settings.
#[derive(Clone, Copy, Debug)]
pub struct ModuleKind {
    pub kind: &'static str,
    pub description: &'static str,
    pub settings: &'static [Setting],
}

impl Setting {
    /// A setting: its key, type, default (as text) and what it does.
    pub const fn new(
        name: &'static str,
        ty: SettingType,
        default: &'static str,
        description: &'static str,
    ) -> Setting {
        Setting { name, ty, default, description }
    }
}

const fn s(
    name: &'static str,
    ty: SettingType,
    default: &'static str,
    description: &'static str,
) -> Setting {
    Setting::new(name, ty, default, description)
}

use SettingType::*;

/// Keys every `[modules.NAME]` table may have, whatever its kind.
pub const COMMON: &[Setting] = &[
    s(
        "kind",
        String,
        "the table's NAME",
        "Which module runs: sim, mavlink, video, codec, input, distrib, map, script, process, window_manager, widgets, map_view or video_windows",
    ),
    s(
        "enabled",
        Bool,
        "true",
        "false: the module is not started; naming a core module (input, window_manager, widgets, map_view, video_windows) turns it off",
    ),
    s(
        "optional",
        Bool,
        "false",
        "true: the run goes on without this module if it cannot start, and exits 0; otherwise a module that fails to start makes `mocu run` exit 1",
    ),
    s(
        "order",
        Int,
        "after the others",
        "Start order (lower first); then sim, mavlink, video, then by name",
    ),
];

/// Every module kind `mocu run` knows.
pub const MODULES: &[ModuleKind] = &[
    ModuleKind {
        kind: "sim",
        description: "The built-in simulator: vehicles under root.vehicles",
        settings: &[
            s(
                "vehicles",
                Names,
                "usv1, usv2, ugv1, uav1",
                "The vehicles, in the order they appear; each name starts with its type: usv, ugv or uav (replaces usv, ugv, uav)",
            ),
            s(
                "usv",
                Int,
                "2",
                "How many surface vehicles (usv1, usv2, …), when `vehicles` is not given",
            ),
            s("ugv", Int, "1", "How many ground vehicles (ugv1, …), when `vehicles` is not given"),
            s("uav", Int, "1", "How many air vehicles (uav1, …), when `vehicles` is not given"),
            s("seed", Int, "1", "Random seed: the same seed gives the same run"),
            s("appear_every", Number, "0.5", "Seconds between two vehicles appearing"),
            s("rate_hz", Number, "20", "Simulation steps per second, 0.01 to 1000"),
            s("camera_fps", Number, "10", "Simulated camera frames per second"),
            s("camera_width", Int, "640", "Simulated camera width in px, 1 to 1920"),
            s("camera_height", Int, "480", "Simulated camera height in px, 1 to 1080"),
            s("origin_lat", Number, "32.71", "Latitude of the local origin, in degrees"),
            s("origin_lon", Number, "-117.24", "Longitude of the local origin, in degrees"),
            s(
                "autostart",
                Bool,
                "true",
                "The first vehicle of each type arms and patrols on its own",
            ),
        ],
    },
    ModuleKind {
        kind: "mavlink",
        description: "MAVLink 2 over UDP: vehicles heard appear as root.vehicles.mav<sysid>",
        settings: &[
            s("address", String, "0.0.0.0:14550", "UDP address to listen on (HOST:PORT)"),
            s("command_timeout_ms", Int, "1000", "How long to wait for a command's answer, in ms"),
            s("attempts", Int, "3", "How many times a command is sent before it fails, 1 to 100"),
            s(
                "link_timeout_ms",
                Int,
                "3000",
                "Silence after which a vehicle's link is lost, in ms",
            ),
            s("max_vehicles", Int, "32", "Vehicles this link holds at most; more are refused"),
            s(
                "forget_after_ms",
                Int,
                "60000",
                "Silence after which a vehicle is forgotten (its object removed), in ms",
            ),
            s(
                "proof_heartbeats",
                Int,
                "3",
                "Heartbeats in sequence from one address before anything is sent to it",
            ),
            s("max_send_rate", Int, "200", "Datagrams sent per second at most"),
            s(
                "signing_key",
                String,
                "none",
                "MAVLink 2 signing key (64 hex digits, or a passphrase hashed with SHA-256); with one, only signed frames are accepted and what is sent is signed",
            ),
            s("signing_link_id", Int, "0", "The link id put on the frames this link signs"),
        ],
    },
    ModuleKind {
        kind: "video",
        description: "Video receiver (RTP/H.264 over UDP): streams under root.cameras",
        settings: &[
            s("address", String, "0.0.0.0:5600", "UDP address to listen on (HOST:PORT)"),
            s("camera", String, "none", "Path of the camera object the stream belongs to"),
            s("feeds", String, "auto", "Which feeds to receive"),
            s("decode", Bool, "true", "Decode frames (false: count them only)"),
            s("source", String, "any", "The only sender heard: HOST or HOST:PORT"),
            s("ssrc", Int, "any", "The only RTP stream heard, by its SSRC"),
            s("silence_ms", Int, "2000", "Silence after which the next stream may be heard"),
            s("reorder", Int, "8", "RTP packets held to put them back in order, 1 to 1024"),
            s("reorder_ms", Int, "100", "Longest wait for a missing RTP packet, in ms"),
            s("max_width", Int, "4096", "Widest frame decoded (px); wider ones are refused"),
            s("max_height", Int, "4096", "Tallest frame decoded (px); taller ones are refused"),
            s("max_unit_kb", Int, "32768", "Largest encoded frame kept, in KiB"),
        ],
    },
    ModuleKind {
        kind: "codec",
        description: "Decodes one camera's frames",
        settings: &[s("source", String, "(required)", "Path of the camera object to decode")],
    },
    ModuleKind {
        kind: "input",
        description: "Operator input: gamepads, keyboard, scripted input",
        settings: &[
            s("rate_hz", Number, "50", "Axis sampling rate, 1 to 250"),
            s("double_ms", Number, "300", "Longest gap of a double press, in ms, 10 to 2000"),
            s("script", String, "none", "A file of scripted input events (for trials and tests)"),
            s("toasts", Int, "5", "How many input toasts are kept, 0 to 20"),
            s("gilrs", Bool, "true", "Read gamepads"),
            s("auto_select", Bool, "true", "Select the first vehicle when it appears"),
        ],
    },
    ModuleKind {
        kind: "distrib",
        description: "The world model shared over Zenoh with other OCUs and adapters (docs/distribution.md)",
        settings: &[
            s(
                "listen",
                Names,
                "none",
                "Zenoh endpoints to listen on, e.g. [\"tcp/127.0.0.1:7447\"]",
            ),
            s("connect", Names, "none", "Zenoh endpoints to connect to"),
            s(
                "share",
                Names,
                "none",
                "Object paths whose subtrees are published, e.g. [\"vehicles\"]",
            ),
            s(
                "streams",
                Names,
                "none",
                "Listeners of the shared subtrees whose messages are shared, * for any one name, e.g. [\"vehicles.*.cameras.drive\"]",
            ),
            s(
                "stream_rate_hz",
                Number,
                "5",
                "The most messages a second shared per stream (a camera's frame rate over the network)",
            ),
            s("operator", String, "none", "The operator's name, sent with every call"),
            s(
                "site",
                String,
                "the operator",
                "This process's name on the key space (mocu/<site>/...)",
            ),
            s(
                "call_timeout_ms",
                Int,
                "10000",
                "How long a call to another site waits for its answer, in ms",
            ),
            s("lease_ms", Int, "2000", "Silence after which a peer is taken as gone, in ms"),
            s(
                "join_timeout_ms",
                Int,
                "10000",
                "How long a joiner waits for the first snapshot, in ms",
            ),
            s(
                "tls_ca",
                String,
                "none",
                "PEM file of the CA that signs every peer's certificate (mutual TLS)",
            ),
            s(
                "tls_cert",
                String,
                "none",
                "PEM file of this site's certificate (its common name: the operator)",
            ),
            s("tls_key", String, "none", "PEM file of this site's private key"),
            s(
                "acl",
                Names,
                "none",
                "Who may call this site's methods: [\"alice: vehicles\", \"bob: vehicles.usv2\"] (needs TLS)",
            ),
            s(
                "control",
                Bool,
                "true where vehicles are shared",
                "Control arbitration of the shared vehicles (docs/distribution.md)",
            ),
            s(
                "takeover",
                String,
                "allowed",
                "What a takeover of a held vehicle does: allowed, denied or ask (the holder answers)",
            ),
            s("takeover_allowed", Names, "none", "Vehicles whose takeover is allowed"),
            s("takeover_denied", Names, "none", "Vehicles whose takeover is denied"),
            s("takeover_ask", Names, "none", "Vehicles whose holder is asked for a takeover"),
            s(
                "free",
                String,
                "open",
                "A vehicle nobody holds takes commands from anyone (open) or none (closed)",
            ),
            s(
                "release_after_ms",
                Int,
                "5000",
                "How long after its site disappears a holder loses control, in ms",
            ),
            s("ask_timeout_ms", Int, "8000", "How long a holder has to answer a takeover, in ms"),
        ],
    },
    ModuleKind {
        kind: "map",
        description: "The map's data: GeoJSON overlays under root.map.features, raster tiles (docs/map.md)",
        settings: &[
            s(
                "overlays",
                Names,
                "none",
                "GeoJSON files (coastline, piers, buoys, zones, no-go areas), relative to the profile",
            ),
            s(
                "tiles",
                String,
                "none",
                "An MBTiles file or a z/x/y folder of PNG tiles (Web Mercator), relative to the profile",
            ),
            s("origin_lat", Number, "32.71", "Latitude of the local frame's origin, in degrees"),
            s("origin_lon", Number, "-117.24", "Longitude of the local frame's origin, in degrees"),
        ],
    },
    ModuleKind {
        kind: "script",
        description: "A script module: a .js or .rhai file run against the DataServer (docs/scripting.md)",
        settings: &[
            s(
                "file",
                String,
                "required",
                "The script, relative to the profile; its extension picks the engine (.js, .rhai)",
            ),
            s(
                "operations",
                Int,
                "1000000",
                "Operations one run or callback may take; past them the script is stopped",
            ),
            s("memory_kb", Int, "16384", "Memory the script may hold, in KiB (64 to 4194304)"),
            s("files", Bool, "false", "Grants `import` of other scripts from the script's folder"),
        ],
    },
    ModuleKind {
        kind: "widgets",
        description: "The widget renderer: draws the layout's widgets windows (a core module, started unless turned off)",
        settings: &[
            s("accepted_ms", Int, "1500", "How long an accepted call's green outline shows, in ms"),
            s(
                "refused_ms",
                Int,
                "5000",
                "How long a refused or failed call's red outline and reason show, in ms",
            ),
        ],
    },
    ModuleKind {
        kind: "window_manager",
        description: "The window manager's behaviours: swap, animate and animate_eased on root.display, which layouts and modules call to move windows (a core module, started unless turned off: then a layout's swap happens at once)",
        settings: &[s(
            "animate",
            Bool,
            "true",
            "false: every swap and move happens at once instead of over its duration",
        )],
    },
    ModuleKind {
        kind: "map_view",
        description: "The map painter: draws the layout's map windows from root.vehicles and root.map (a core module, started unless turned off)",
        settings: &[],
    },
    ModuleKind {
        kind: "video_windows",
        description: "The video windows' painter: draws the layout's video windows from the cameras (a core module, started unless turned off)",
        settings: &[
            s(
                "stale_ms",
                Int,
                "1000",
                "No frame for this long: the last one is marked STALE, in ms",
            ),
            s("no_video_ms", Int, "3000", "No frame for this long: NO VIDEO, in ms"),
        ],
    },
    ModuleKind {
        kind: "process",
        description: "A module in any language run as a child process, joining over Zenoh (docs/modules.md)",
        settings: &[
            s(
                "command",
                Names,
                "required",
                "The program and its arguments, e.g. [\"python3\", \"examples/geofence.py\"]",
            ),
            s(
                "connect",
                String,
                "the OCU's own endpoint",
                "The Zenoh endpoint handed to the command as MOCU_CONNECT",
            ),
            s("restart_backoff_ms", Int, "500", "Wait before the first restart, in ms; doubles"),
            s("max_backoff_ms", Int, "30000", "The longest wait between restarts, in ms"),
        ],
    },
];

/// Kinds a project declared for its own build ([`declare`]).
static DECLARED: std::sync::RwLock<Vec<&'static ModuleKind>> = std::sync::RwLock::new(Vec::new());

/// Declares a module kind of a project's own build of `mocu` (the one its registry has), so
/// that its profiles are checked against its settings as the stock kinds' are: without it,
/// a profile naming the kind is refused. A kind declared again replaces its declaration; a
/// stock kind's name declared replaces the stock declaration (a project's own `map_view`).
pub fn declare(kind: ModuleKind) {
    let kind: &'static ModuleKind = Box::leak(Box::new(kind));
    let mut declared = DECLARED.write().unwrap_or_else(|e| e.into_inner());
    declared.retain(|k| k.kind != kind.kind);
    declared.push(kind);
}

/// The declaration of a module kind: a declared one ([`declare`]) or a stock one.
pub fn kind(name: &str) -> Option<&'static ModuleKind> {
    let declared = DECLARED.read().unwrap_or_else(|e| e.into_inner());
    declared
        .iter()
        .copied()
        .find(|m| m.kind == name)
        .or_else(|| MODULES.iter().find(|m| m.kind == name))
}

/// Every kind known: the stock ones, then those a project declared ([`declare`]), each once.
pub fn kinds() -> Vec<&'static str> {
    let declared = DECLARED.read().unwrap_or_else(|e| e.into_inner());
    let mut out: Vec<&'static str> = MODULES.iter().map(|m| m.kind).collect();
    out.extend(declared.iter().map(|m| m.kind).filter(|k| !MODULES.iter().any(|m| m.kind == *k)));
    out
}

impl ModuleKind {
    /// The declaration of one of its keys (or a common key).
    pub fn setting(&self, key: &str) -> Option<&'static Setting> {
        self.settings.iter().chain(COMMON).find(|s| s.name == key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kind_a_project_declared_is_listed_and_suggested_with_the_stock_ones() {
        declare(ModuleKind { kind: "plot_map_t", description: "a test kind", settings: &[] });
        let all = kinds();
        assert!(all.contains(&"plot_map_t") && all.contains(&"map_view"), "{all:?}");
        assert_eq!(all.iter().filter(|k| **k == "plot_map_t").count(), 1);
        let mut diags = crate::Diagnostics::new();
        let mut sources = crate::SourceMap::new();
        let text = "[profile]\nname = \"p\"\nlayouts = []\n\n[modules.p]\nkind = \"plot_mapt\"\n";
        let loader = crate::MemoryLoader::new().with("project.toml", text);
        crate::check_profile("project.toml", text.into(), &loader, &mut sources, &mut diags);
        let help = diags.into_vec().into_iter().find_map(|d| d.help).unwrap_or_default();
        assert!(help.contains("did you mean `plot_map_t`?"), "{help}");
        assert!(help.contains("`plot_map_t`;"), "listed last: {help}");
    }
}
