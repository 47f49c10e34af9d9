//! Hot reload, end to end: a test edits the layout file the way editors do and sees the
//! change in `root.display` and in the rendered frame; broken edits keep the old display
//! and raise the banner; a storm of random edits leaves exactly what a fresh load gives.
use mocu_dataserver::*;
use mocu_display::{BackendChoice, Display, DisplayOptions};
use mocu_hotreload::*;
use mocu_layout::{EventSink, LayoutConfig, MemorySink};
use mocu_widgets::{Library, RendererConfig, WidgetRenderer};
use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender};
use std::time::Duration;

fn layout_text(colour: &str, width: u32, extra: &str) -> String {
    format!(
        r#"
component Box(c: colour) {{ rect 0 0 w h  fill c }}
window hud {{ layer 10 rect 0 0 100% 100% }}
in hud {{
  a: Box {{ at 10 60 {width} 40  c {colour} }}
  b: Box {{ at 10 110 100 40  c #0000ff }}
{extra}}}
"#
    )
}

struct Rig {
    ds: DataServer,
    reloader: Reloader,
    display: Display,
    _renderer: Arc<WidgetRenderer>,
    _dir: tempfile::TempDir,
    path: std::path::PathBuf,
    sink: Arc<MemorySink>,
    /// A message each time a reload has done something a test may wait for.
    reloaded: Receiver<()>,
}

/// Records into a `MemorySink` and says so on a channel: the reload outcome a test waits for.
struct Signalling {
    memory: Arc<MemorySink>,
    tx: Sender<()>,
}

impl EventSink for Signalling {
    fn record(&self, event: &str, fields: &[(&str, Value)]) {
        self.memory.record(event, fields);
        let _ = self.tx.send(());
    }
}

fn rig(text: &str) -> Rig {
    rig_in(tempfile::tempdir().unwrap(), text)
}

/// A rig whose layout `hud.mocu` is written in `dir` (which may hold its project).
fn rig_in(dir: tempfile::TempDir, text: &str) -> Rig {
    let path = dir.path().join("hud.mocu");
    std::fs::write(&path, text).unwrap();
    let ds = DataServer::default();
    let display =
        Display::new(&ds, DisplayOptions::new(320, 200).backend(BackendChoice::Cpu)).unwrap();
    let (bundle, _) = mocu_language::load_target(&path).unwrap_or_else(|e| panic!("{e}"));
    let renderer = Arc::new(
        WidgetRenderer::start(
            &ds,
            Library::compile(&bundle.layouts[0].program, true).unwrap(),
            RendererConfig::default(),
        )
        .unwrap(),
    );
    let r2 = renderer.clone();
    let (tx, reloaded) = std::sync::mpsc::channel();
    let tx2 = tx.clone();
    let options = ReloaderOptions {
        config: LayoutConfig {
            screen: (320.0, 200.0),
            tick: Duration::from_millis(1),
            ..LayoutConfig::default()
        },
        layout: None,
        on_components: Some(Arc::new(move |p| {
            if let Ok(lib) = Library::compile(p, true) {
                r2.replace_library(lib);
            }
            // The last step of a good reload.
            let _ = tx2.send(());
        })),
    };
    let sink = Arc::new(MemorySink::default());
    let signalling = Arc::new(Signalling { memory: sink.clone(), tx: tx.clone() });
    let reloader = Reloader::start(&ds, &path, &bundle, options, signalling).unwrap();
    // A refused or failed reload ends by raising the banner.
    let diagnostics = ds.resolve(&["operator", "diagnostics"]).unwrap();
    ds.subscribe(Topic::properties(diagnostics), move |_| {
        let _ = tx.send(());
    })
    .unwrap();
    Rig { ds, reloader, display, _renderer: renderer, _dir: dir, path, sink, reloaded }
}

impl Rig {
    fn frame(&mut self) -> (u8, u8, u8) {
        self.reloader.with_layout(|l| l.settle());
        self.ds.quiesce();
        self.display.frame();
        let f = self.display.read_frame();
        let p = f.pixel(20, 70).unwrap();
        (p.red(), p.green(), p.blue())
    }

    fn width_of_a(&self) -> Option<Value> {
        let a = self.ds.resolve(&["display", "hud", "a"])?;
        self.ds.try_get(a, PropName::new("w"))
    }

    /// Waits until `f` holds, checking it after each reload (the file watcher's event, then
    /// the reload, are what it waits for); the 30 s bound only turns a hang into a failure.
    fn wait(&mut self, what: &str, mut f: impl FnMut(&mut Rig) -> bool) {
        while !f(self) {
            if self.reloaded.recv_timeout(Duration::from_secs(30)).is_err() {
                panic!("no reload brought {what}");
            }
        }
    }

    fn banner_active(&self) -> bool {
        self.ds
            .resolve(&["operator", "diagnostics"])
            .and_then(|d| self.ds.try_get(d, PropName::new("active")))
            == Some(Value::Bool(true))
    }
}

/// Saves like vim or VS Code: write a new file, then rename it over the old one.
fn save_by_rename(path: &Path, text: &str) {
    let tmp = path.with_extension("mocu.swp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

#[test]
fn saving_a_layout_changes_the_display_and_the_frame_at_once() {
    let mut r = rig(&layout_text("#ff0000", 100, ""));
    assert_eq!(r.frame(), (255, 0, 0));
    r.reloader.watch().unwrap();
    let b = r.ds.resolve(&["display", "hud", "b"]).unwrap();
    std::fs::write(&r.path, layout_text("#00ff00", 100, "")).unwrap();
    r.wait("the new colour on screen", |r| r.frame() == (0, 255, 0));
    assert_eq!(
        r.ds.resolve(&["display", "hud", "b"]).unwrap(),
        b,
        "only `a` changed: `b` keeps its object"
    );
    // An editor that replaces the file by rename.
    save_by_rename(&r.path, &layout_text("#00ff00", 150, ""));
    r.wait("the new width", |r| r.width_of_a() == Some(Value::Float(150.0)));
    // Deleted and created again.
    std::fs::remove_file(&r.path).unwrap();
    r.wait("the missing file reported", |r| r.banner_active());
    std::fs::write(&r.path, layout_text("#ffff00", 150, "")).unwrap();
    r.wait("yellow", |r| r.frame() == (255, 255, 0));
    assert!(!r.sink.of("reload").is_empty());
}

#[test]
fn a_broken_save_keeps_the_last_good_layout_and_raises_the_banner_until_fixed() {
    let mut r = rig(&layout_text("#ff0000", 100, ""));
    // Settled first: the first load's publications (the window's `revision`) are all in.
    assert_eq!(r.frame(), (255, 0, 0));
    r.reloader.watch().unwrap();
    let before = r.ds.snapshot(r.ds.resolve(&["display", "hud"]).unwrap()).unwrap();
    // A partial write: the file is cut in the middle of a widget.
    let text = layout_text("#00ff00", 100, "");
    let cut = text.find("c #00ff00").unwrap();
    std::fs::write(&r.path, &text[..cut]).unwrap();
    r.wait("the banner", |r| {
        r.ds.resolve(&["operator", "diagnostics"])
            .and_then(|d| r.ds.try_get(d, PropName::new("active")))
            == Some(Value::Bool(true))
    });
    assert_eq!(r.frame(), (255, 0, 0), "the old frame stays");
    assert_eq!(r.ds.snapshot(r.ds.resolve(&["display", "hud"]).unwrap()).unwrap(), before);
    let d = r.ds.resolve(&["operator", "diagnostics"]).unwrap();
    let text_shown = r.ds.get(d, "text").unwrap().to_string();
    assert!(text_shown.contains("hud.mocu:"), "file:line:col in the banner: {text_shown}");
    let banner = r.ds.resolve(&["display", "diagnostics"]).unwrap();
    assert_eq!(r.ds.get(banner, "visible").unwrap(), Value::Bool(true));
    let logged = r.sink.of("diagnostic");
    assert!(
        logged.iter().any(|f| f.iter().any(|(k, v)| k == "line" && v.as_i64().is_some())),
        "{logged:?}"
    );
    // The fix, a moment later.
    std::fs::write(&r.path, &text).unwrap();
    r.wait("the fix on screen", |r| r.frame() == (0, 255, 0));
    assert_eq!(r.ds.get(banner, "visible").unwrap(), Value::Bool(false));
}

#[test]
fn a_save_with_a_window_beyond_the_display_limits_is_refused_and_the_trial_display_stays() {
    let mut r = rig(&layout_text("#ff0000", 100, ""));
    assert_eq!(r.frame(), (255, 0, 0));
    r.reloader.watch().unwrap();
    let huge = layout_text("#00ff00", 100, "")
        + "window huge { layer 20  rect 0 0 100000000 100000000 }\n";
    std::fs::write(&r.path, &huge).unwrap();
    r.wait("the banner", |r| r.banner_active());
    let d = r.ds.resolve(&["operator", "diagnostics"]).unwrap();
    let shown = r.ds.get(d, "text").unwrap().to_string();
    assert!(shown.contains("hud.mocu:8:34: 100000000 px is beyond the display's limit"), "{shown}");
    assert_eq!(r.frame(), (255, 0, 0), "the last good layout stays on screen");
}

#[test]
fn a_remote_tool_can_ask_for_a_reload_through_the_dataserver() {
    let mut r = rig(&layout_text("#ff0000", 100, ""));
    std::fs::write(&r.path, layout_text("#0000ff", 100, "")).unwrap();
    let op = r.ds.resolve(&["operator"]).unwrap();
    assert!(r.ds.call_wait(op, "reload", vec![], None).is_accepted());
    r.wait("blue", |r| r.frame() == (0, 0, 255));
}

/// The display subtree without GUIDs (they differ between two worlds).
fn shape(s: &Snapshot) -> String {
    let mut out = format!("{}:{}:{}[", s.name, s.kind, s.subtype);
    for (n, v) in &s.properties {
        if n != "revision" {
            out.push_str(&format!("{n}={v:?};"));
        }
    }
    let mut kids: Vec<String> = s.children.iter().map(shape).collect();
    kids.sort();
    out.push_str(&kids.join(","));
    out.push(']');
    out
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

fn random_layout(rng: &mut Rng) -> String {
    let colours = ["#ff0000", "#00ff00", "#123456", "#abcdef"];
    let mut extra = String::new();
    for i in 0..rng.below(4) {
        extra.push_str(&format!(
            "  x{i}: Box {{ at {} 160 20 20  c {} }}\n",
            10 + 30 * i,
            colours[rng.below(4) as usize]
        ));
    }
    let mut text = layout_text(colours[rng.below(4) as usize], 50 + rng.below(100) as u32, &extra);
    if rng.below(3) == 0 {
        // Break it: cut it, or drop a character.
        let at = rng.below(text.len() as u64) as usize;
        let at = (0..=at).rev().find(|i| text.is_char_boundary(*i)).unwrap_or(0);
        if rng.below(2) == 0 {
            text.truncate(at);
        } else {
            text.remove(at);
        }
    }
    text
}

#[test]
fn a_thousand_random_edits_leave_what_a_fresh_load_of_the_last_file_gives() {
    let mut r = rig(&layout_text("#ff0000", 100, ""));
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let mut last = String::new();
    for i in 0..1000 {
        last = random_layout(&mut rng);
        std::fs::write(&r.path, &last).unwrap();
        let _ = r.reloader.reload_now();
        if i % 97 == 0 {
            r.frame();
        }
    }
    // Make sure the last file is a good one, then compare with a fresh world.
    if mocu_language::load_target(&r.path).is_err() {
        last = layout_text("#abcdef", 77, "  x0: Box { at 10 160 20 20  c #123456 }\n");
        std::fs::write(&r.path, &last).unwrap();
    }
    assert!(matches!(r.reloader.reload_now(), Outcome::Reloaded(_)));
    r.frame();
    let fresh = rig(&last);
    fresh.reloader.with_layout(|l| l.settle());
    let shape_of =
        |ds: &DataServer| shape(&ds.snapshot(ds.resolve(&["display", "hud"]).unwrap()).unwrap());
    assert_eq!(shape_of(&r.ds), shape_of(&fresh.ds));
    r.ds.quiesce();
    fresh.ds.quiesce();
    assert_eq!(
        r.ds.subscription_count(),
        fresh.ds.subscription_count(),
        "no subscription left behind"
    );
    assert_eq!(r.reloader.reloads(), 1001);
}

#[test]
fn a_burst_of_saves_through_the_watcher_settles_on_the_last_one() {
    let mut r = rig(&layout_text("#ff0000", 100, ""));
    r.reloader.watch().unwrap();
    let mut rng = Rng(7);
    for _ in 0..50 {
        std::fs::write(&r.path, random_layout(&mut rng)).unwrap();
    }
    let last = layout_text("#00ff00", 120, "  x0: Box { at 10 160 20 20  c #abcdef }\n");
    std::fs::write(&r.path, &last).unwrap();
    r.wait("the last save on screen", |r| {
        r.frame() == (0, 255, 0) && r.width_of_a() == Some(Value::Float(120.0))
    });
    assert!(r.reloader.reloads() < 51, "bursts are coalesced: {} reloads", r.reloader.reloads());
}

#[test]
fn a_schema_edit_is_hot_reloaded_even_from_a_multi_line_array_of_the_project() {
    let dir = tempfile::tempdir().unwrap();
    let profile =
        "[profile]\nlayouts = []\nschemas = [\n  \"schemas/a.toml\",\n  \"schemas/usv.toml\",\n]\n";
    std::fs::write(dir.path().join("project.toml"), profile).unwrap();
    std::fs::create_dir(dir.path().join("schemas")).unwrap();
    std::fs::write(dir.path().join("schemas/a.toml"), "[types.other]\n").unwrap();
    let schema = |prop: &str| {
        format!(
            "[[instances]]\npath = \"root.vehicles.usv*\"\ntype = \"usv\"\n[types.usv.properties]\n{prop} = {{ type = \"float\" }}\n"
        )
    };
    let usv = dir.path().join("schemas/usv.toml");
    std::fs::write(&usv, schema("fuel")).unwrap();
    let watch = "}\nwatch low { when root.vehicles.usv1.fuel < 0.2 then alert warning \"low\" ";
    let r = rig_in(dir, &layout_text("#ff0000", 100, watch));
    let files = r.reloader.files();
    for f in ["project.toml", "a.toml", "usv.toml"] {
        assert!(files.iter().any(|p| p.ends_with(f)), "{f} is followed: {files:?}");
    }
    r.reloader.watch().unwrap();
    // The schema renames the property: the layout no longer checks, the banner says why.
    std::fs::write(&usv, schema("fuel_level")).unwrap();
    let mut r = r;
    r.wait("the banner", |r| {
        r.ds.resolve(&["operator", "diagnostics"])
            .and_then(|d| r.ds.try_get(d, PropName::new("active")))
            == Some(Value::Bool(true))
    });
    let d = r.ds.resolve(&["operator", "diagnostics"]).unwrap();
    let shown = r.ds.get(d, "text").unwrap().to_string();
    assert!(shown.contains("fuel"), "{shown}");
}

/// `n` more boxes in `hud`: a layout that takes the checker a while.
fn many_boxes(n: usize) -> String {
    (0..n).map(|i| format!("  x{i}: Box {{ at {} 10 4 4  c #00ff00 }}\n", i % 300)).collect()
}

#[test]
fn a_save_over_the_reload_limits_is_refused_like_a_broken_layout_and_the_last_good_one_stays() {
    let mut r = rig(&layout_text("#ff0000", 100, ""));
    assert_eq!(r.frame(), (255, 0, 0));
    let good = std::fs::metadata(&r.path).unwrap().len();
    r.reloader.set_limits(ReloadLimits { max_source_bytes: good + 64, ..ReloadLimits::default() });

    // Too large to be read into the checker.
    std::fs::write(&r.path, layout_text("#00ff00", 100, &many_boxes(50))).unwrap();
    match r.reloader.reload_now() {
        Outcome::Failed(why) => assert!(why.contains("bytes, over the"), "{why}"),
        other => panic!("an oversized layout: {other:?}"),
    }
    assert!(r.banner_active());
    assert_eq!(r.frame(), (255, 0, 0), "the last good layout stays");

    // A check that cannot end within its time: none may take any time at all here, and this
    // one has thousands of widgets to check.
    std::fs::write(&r.path, layout_text("#0000ff", 100, &many_boxes(3_000))).unwrap();
    r.reloader.set_limits(ReloadLimits { check_time: Duration::ZERO, ..ReloadLimits::default() });
    match r.reloader.reload_now() {
        Outcome::Failed(why) => assert!(why.contains("checking took longer than"), "{why}"),
        other => panic!("a check past its time: {other:?}"),
    }
    assert_eq!(r.frame(), (255, 0, 0), "the last good layout stays");

    // Within the limits again, a layout loads.
    std::fs::write(&r.path, layout_text("#00ff00", 100, &many_boxes(50))).unwrap();
    r.reloader.set_limits(ReloadLimits::default());
    assert!(matches!(r.reloader.reload_now(), Outcome::Reloaded(_)));
    assert_eq!(r.frame(), (0, 255, 0));
    assert!(!r.banner_active());
}

/// Fires the first binding of the layout (its `fire(value)` method) and waits for the world;
/// whether the binding took it (a binding being replaced by a reload in progress does not).
fn fire_first_binding(r: &Rig) -> bool {
    let bindings = r.ds.resolve(&["display", "bindings"]).expect("bindings");
    let Some(b) = r.ds.children(bindings).unwrap_or_default().first().copied() else {
        return false;
    };
    let took = r.ds.call_wait(b, "fire", vec![Value::Float(1.0)], None).is_accepted();
    r.reloader.with_layout(|l| l.settle());
    took
}

#[test]
fn a_saved_script_action_runs_its_new_text_and_a_script_syntax_error_is_refused_in_the_banner() {
    mocu_layout::install_script_checker();
    let with_script = |body: &str| {
        format!(
            "{}bind keyboard {{ key space -> #js: {{ {body} }} }}\n",
            layout_text("#ff0000", 100, "")
        )
    };
    let mut r = rig(&with_script("mocu.write(\"out.word\", \"old\");"));
    r.ds.create_object(Guid::ROOT, ObjectInfo::new("out", "folder")).unwrap();
    let out = r.ds.resolve(&["out"]).unwrap();
    assert_eq!(r.frame(), (255, 0, 0));
    assert!(fire_first_binding(&r));
    assert_eq!(r.ds.get(out, "word").unwrap(), Value::str("old"));
    r.reloader.watch().unwrap();
    std::fs::write(&r.path, with_script("mocu.write(\"out.word\", \"new\");")).unwrap();
    r.wait("the new script", |r| {
        fire_first_binding(r) && r.ds.get(out, "word").unwrap() == Value::str("new")
    });
    // A syntax error in the script: refused, the banner names the script's line and column.
    std::fs::write(&r.path, with_script("mocu.write(\"out.word\" \"x\");")).unwrap();
    r.wait("the banner", |r| r.banner_active());
    let d = r.ds.resolve(&["operator", "diagnostics"]).unwrap();
    let shown = r.ds.get(d, "text").unwrap().to_string();
    let line = with_script("").lines().count();
    assert!(shown.contains(&format!("hud.mocu:{line}:")), "{shown}");
    assert!(shown.contains("js script"), "{shown}");
    assert!(fire_first_binding(&r));
    assert_eq!(r.ds.get(out, "word").unwrap(), Value::str("new"), "the last good script stays");
}
