use crate::banner;
use crate::limits::{ReloadLimits, check_bounded};
use mocu_dataserver::{CallOutcome, DataServer, MethodSpec, ObjectInfo};
use mocu_language::{FsLoader, Severity};
use mocu_layout::{EventSink, Layout, LayoutConfig, ReloadStats};
use mocu_value::{Guid, Value};
use parking_lot::Mutex;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a reload did.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// The new program runs.
    Reloaded(ReloadStats),
    /// The target has errors (rendered, human form); the last good layout stays.
    Refused { errors: usize, rendered: String },
    /// The target could not be read or run at all; the last good layout stays.
    Failed(String),
}

/// Called with the components of each newly loaded program.
pub type OnComponents = Arc<dyn Fn(&mocu_language::Program) + Send + Sync>;

#[derive(Clone)]
pub struct ReloaderOptions {
    pub config: LayoutConfig,
    /// Which of a profile's layouts runs (file name or stem); the first when `None`.
    pub layout: Option<String>,
    /// Called with the components of each newly loaded program (the widget renderer's
    /// library is rebuilt from them).
    pub on_components: Option<OnComponents>,
}

/// The running layout of a target, and the means to reload it.
pub struct Reloader {
    pub(crate) inner: Arc<Inner>,
}

pub(crate) struct Inner {
    pub(crate) ds: DataServer,
    pub(crate) target: PathBuf,
    pub(crate) options: ReloaderOptions,
    pub(crate) sink: Arc<dyn EventSink>,
    pub(crate) state: Mutex<State>,
    /// Set when the reloader goes: a check that ends after it swaps nothing in.
    pub(crate) stopping: AtomicBool,
    /// One check at a time (`limits.rs`).
    checking: crate::limits::Token,
}

pub(crate) struct State {
    layout: Option<Layout>,
    /// Every file the running target depends on.
    pub(crate) files: Vec<PathBuf>,
    pub(crate) watcher: Option<crate::watcher::Watcher>,
    reloads: u64,
    limits: ReloadLimits,
}

/// How long dropping a reloader waits for a swap in progress before leaving the layout to the
/// thread doing it.
const SWAP_WAIT: std::time::Duration = std::time::Duration::from_millis(200);

/// The layout to run from a bundle: by name, else the first.
pub fn choose(bundle: &mocu_language::Bundle, name: Option<&str>) -> Option<usize> {
    let layouts = &bundle.layouts;
    match name {
        None => (!layouts.is_empty()).then_some(0),
        Some(n) => layouts.iter().position(|l| {
            let p = Path::new(&l.path);
            l.path == n
                || p.file_name().is_some_and(|f| f == n)
                || p.file_stem().is_some_and(|f| f == n)
        }),
    }
}

impl Reloader {
    /// Runs `bundle` (already checked from `target`) and keeps `target` to reload from.
    pub fn start(
        ds: &DataServer,
        target: &Path,
        bundle: &mocu_language::Bundle,
        options: ReloaderOptions,
        sink: Arc<dyn EventSink>,
    ) -> Result<Reloader, String> {
        let index = choose(bundle, options.layout.as_deref()).ok_or_else(|| {
            format!(
                "no layout `{}` in {}",
                options.layout.as_deref().unwrap_or(""),
                target.display()
            )
        })?;
        let chosen = &bundle.layouts[index];
        let layout = Layout::load(ds, &chosen.program, options.config.clone(), sink.clone())
            .map_err(|e| e.to_string())?;
        if let Some(f) = &options.on_components {
            f(&chosen.program);
        }
        let files = dependencies(target, bundle, index);
        let inner = Arc::new(Inner {
            ds: ds.clone(),
            target: target.to_path_buf(),
            options,
            sink,
            state: Mutex::new(State {
                layout: Some(layout),
                files,
                watcher: None,
                reloads: 0,
                limits: ReloadLimits::default(),
            }),
            stopping: AtomicBool::new(false),
            checking: crate::limits::token(),
        });
        banner::start(ds, inner.options.config.screen);
        publish_reload_method(&inner);
        Ok(Reloader { inner })
    }

    /// Re-checks the target now and swaps the new program in, or keeps the running one and
    /// shows why.
    pub fn reload_now(&self) -> Outcome {
        self.inner.reload()
    }

    /// The files the running target depends on.
    pub fn files(&self) -> Vec<PathBuf> {
        self.inner.state.lock().files.clone()
    }

    /// Runs `f` with the running layout.
    pub fn with_layout<R>(&self, f: impl FnOnce(&Layout) -> R) -> Option<R> {
        self.inner.state.lock().layout.as_ref().map(f)
    }

    /// Starts following the target's files; each change (an editor's burst of events
    /// coalesced) reloads on the watcher's thread.
    pub fn watch(&self) -> Result<(), String> {
        crate::watcher::start(&self.inner)
    }

    /// Bounds each reload's check (default: [`ReloadLimits::default`]).
    pub fn set_limits(&self, limits: ReloadLimits) {
        self.inner.state.lock().limits = limits;
    }

    /// Reloads done so far (successful or not).
    pub fn reloads(&self) -> u64 {
        self.inner.state.lock().reloads
    }
}

impl Drop for Reloader {
    fn drop(&mut self) {
        self.inner.stopping.store(true, Ordering::SeqCst);
        // A swap in progress (compiling a new layout under the lock) is not waited for: the
        // thread doing it drops the layout and the watcher when it ends (`check_and_swap`).
        let taken = self
            .inner
            .state
            .try_lock_for(SWAP_WAIT)
            .map(|mut st| (st.layout.take(), st.watcher.take()));
        drop(taken);
        let _ = self.inner.ds.unpublish_method(Guid::ROOT, "reload");
        if let Some(op) = self.inner.ds.resolve(&["operator"]) {
            let _ = self.inner.ds.unpublish_method(op, "reload");
        }
    }
}

/// The layout file, everything it uses, and its project's profile and schemas (the target
/// itself when it is a profile, else the nearest `project.toml` above the layout).
fn dependencies(target: &Path, bundle: &mocu_language::Bundle, index: usize) -> Vec<PathBuf> {
    let mut files = vec![target.to_path_buf()];
    for f in &bundle.layouts[index].program.files {
        files.push(PathBuf::from(f));
    }
    let t = target.to_string_lossy().replace('\\', "/");
    let profile = if bundle.profile.is_some() {
        Some(t)
    } else {
        mocu_language::project::discover(&t, &FsLoader)
    };
    if let Some(p) = profile {
        files.extend(mocu_language::project::files(&p, &FsLoader).into_iter().map(PathBuf::from));
    }
    files.sort();
    files.dedup();
    files
}

fn publish_reload_method(inner: &Arc<Inner>) {
    let ds = &inner.ds;
    let Some(op) = ds
        .resolve(&["operator"])
        .or_else(|| ds.create_object(Guid::ROOT, ObjectInfo::new("operator", "operator")).ok())
    else {
        return;
    };
    let weak = Arc::downgrade(inner);
    let _ = ds.publish_method_fn(
        op,
        MethodSpec::new("reload").describe("Re-check and reload the running layout"),
        move |_| {
            let Some(inner) = weak.upgrade() else {
                return CallOutcome::Failed("no layout".into());
            };
            // Checking and compiling take a while: off the caller's thread.
            let spawned = std::thread::Builder::new()
                .name("mocu-reload".into())
                .stack_size(mocu_language::COMPILER_STACK)
                .spawn(move || {
                    inner.reload();
                });
            if let Err(e) = spawned {
                return CallOutcome::Failed(format!("cannot start the reload: {e}"));
            }
            CallOutcome::Accepted(vec![])
        },
    );
}

impl Inner {
    pub(crate) fn reload(self: &Arc<Self>) -> Outcome {
        let t0 = std::time::Instant::now();
        let outcome = self.check_and_swap();
        let ms = t0.elapsed().as_secs_f64() * 1000.0;
        let mut st = self.state.lock();
        st.reloads += 1;
        drop(st);
        match &outcome {
            Outcome::Reloaded(stats) => {
                banner::clear(&self.ds);
                eprintln!(
                    "mocu: reloaded {} in {ms:.1} ms ({} kept, {} changed, {} added, {} removed)",
                    self.target.display(),
                    stats.kept,
                    stats.changed,
                    stats.added,
                    stats.removed
                );
            }
            Outcome::Refused { rendered, errors } => {
                eprint!("{rendered}");
                eprintln!(
                    "mocu: {} has {errors} error(s); the last good layout stays on screen",
                    self.target.display()
                );
            }
            Outcome::Failed(why) => {
                eprintln!(
                    "mocu: reload of {} failed: {why}; the last good layout stays on screen",
                    self.target.display()
                );
                banner::show(&self.ds, std::slice::from_ref(why));
                self.sink.record("diagnostic", &[("message", Value::str(why))]);
            }
        }
        outcome
    }

    fn check_and_swap(self: &Arc<Self>) -> Outcome {
        let limits = self.state.lock().limits;
        let (sources, mut diags, bundle) = match check_bounded(&self.target, limits, &self.checking)
        {
            Ok(checked) => checked,
            Err(why) => return Outcome::Failed(why),
        };
        diags.sort();
        let errors = diags.count(Severity::Error);
        let list = diags.into_vec();
        if errors > 0 {
            let rendered = mocu_language::render::human(&sources, &list);
            let mut lines = Vec::new();
            for d in list.iter().filter(|d| d.severity == Severity::Error) {
                let l = d.locate(&sources);
                lines.push(format!("{}:{}:{}: {}", l.file, l.line, l.column, l.message));
                self.sink.record(
                    "diagnostic",
                    &[
                        ("file", Value::str(&l.file)),
                        ("line", Value::Int(l.line as i64)),
                        ("column", Value::Int(l.column as i64)),
                        ("severity", Value::str("error")),
                        ("code", Value::str(&l.code)),
                        ("message", Value::str(&l.message)),
                    ],
                );
            }
            banner::show(&self.ds, &lines);
            return Outcome::Refused { errors, rendered };
        }
        let Some(bundle) = bundle else {
            return Outcome::Failed("the target is not a layout or a profile".into());
        };
        let Some(index) = choose(&bundle, self.options.layout.as_deref()) else {
            return Outcome::Failed("the chosen layout is no longer in the profile".into());
        };
        let program = &bundle.layouts[index].program;
        // Found before the swap (it reads the file system): the banner clears right after it.
        let files = dependencies(&self.target, &bundle, index);
        // The banner goes as the good layout comes, never after it is on screen (a failed
        // swap shows it again).
        if self.stopping.load(Ordering::SeqCst) {
            return Outcome::Failed("stopped".into());
        }
        banner::clear(&self.ds);
        let mut st = self.state.lock();
        let Some(layout) = st.layout.as_ref() else { return Outcome::Failed("stopped".into()) };
        match layout.reload(program) {
            Ok(stats) => {
                st.files = files;
                if self.stopping.load(Ordering::SeqCst) {
                    // The reloader went during the swap: its layout ends here.
                    let left = (st.layout.take(), st.watcher.take());
                    drop(st);
                    drop(left);
                    return Outcome::Failed("stopped".into());
                }
                drop(st);
                if let Some(f) = &self.options.on_components {
                    f(program);
                }
                Outcome::Reloaded(stats)
            }
            Err(e) => Outcome::Failed(e.to_string()),
        }
    }
}
