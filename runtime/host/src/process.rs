//! Process modules: `[modules.NAME] kind = "process"`, `command = ["python3", "x.py"]`. A
//! module in any language runs as a child process and joins the world model through the
//! distributed DataServer (docs/modules.md): it is handed the OCU's Zenoh endpoint as
//! `MOCU_CONNECT` (the `connect` setting, which `mocu run` fills in).
//!
//! The supervisor starts the command, and restarts it whenever it exits, after a back-off
//! that doubles from `restart_backoff_ms` up to `max_backoff_ms`, timed on the DataServer's
//! clock (a `ManualClock` in tests); a run that lasted at least `max_backoff_ms` resets it.
//! A crash of the child never reaches the OCU: it is a report and a restart. While the
//! child is down, the objects it published go stale through the distribution layer's
//! liveliness (docs/distribution.md).
//!
//! `root.modules.NAME` shows `command`, `state` (`running`, `down`, `stopped`,
//! `failed_to_start`), `pid`, `restarts` (starts after the first), `last_exit` (`exit 3`,
//! `signal 9`, or the reason it could not start) and `next_start_in_ms` while down. The
//! child's stdout and stderr go to the OCU's stderr (its stdout is `--dump`'s).

use crate::context::ModuleContext;
use crate::host::{Module, Registry};
use crate::{Level, ModuleSpec};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender};
use mocu_dataserver::Value;
use parking_lot::Mutex;
use std::os::fd::AsFd;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often the watcher thread looks whether its child has exited (std's `Child::wait`
/// would block a `stop`).
const POLL: Duration = Duration::from_millis(20);

/// Registers the `process` module kind.
pub fn register(r: &mut Registry) {
    r.register("process", |spec| Ok(Box::new(ProcessModule::from_spec(spec)?) as Box<dyn Module>));
}

/// A process module's settings and, once started, its supervisor.
pub struct ProcessModule {
    command: Vec<String>,
    connect: String,
    backoff: Duration,
    max_backoff: Duration,
    sup: Option<Arc<Supervisor>>,
}

struct Supervisor {
    ctx: ModuleContext,
    command: Vec<String>,
    connect: String,
    backoff: Duration,
    max_backoff: Duration,
    state: Mutex<State>,
}

struct State {
    /// Set by `stop`: no more restarts.
    stopping: bool,
    /// Tells the running child's watcher to kill it.
    kill: Option<Sender<()>>,
    watcher: Option<std::thread::JoinHandle<()>>,
    starts: i64,
    /// The back-off before the next restart.
    next: Duration,
}

impl ProcessModule {
    /// From the profile's settings: `command` (required, a list of strings), `connect`,
    /// `restart_backoff_ms` (default 500), `max_backoff_ms` (default 30000).
    pub fn from_spec(spec: &ModuleSpec) -> Result<ProcessModule, String> {
        let command: Vec<String> = match spec.settings.get("command") {
            Some(toml::Value::Array(a)) if !a.is_empty() && a.iter().all(|v| v.is_str()) => {
                a.iter().filter_map(|v| v.as_str().map(str::to_string)).collect()
            }
            _ => {
                return Err("a process module needs `command`, a non-empty list of strings, \
                            e.g. [\"python3\", \"examples/geofence.py\"]"
                    .into());
            }
        };
        if !on_path(&command[0]) {
            return Err(format!(
                "`command`: no program `{}` on PATH (a misspelt name? give a path with a `/` \
                 for a program elsewhere)",
                command[0]
            ));
        }
        let ms = |key: &str, default: i64| -> Result<Duration, String> {
            let v = spec.i64_or(key, default).map_err(|e| e.to_string())?;
            if !(1..=86_400_000).contains(&v) {
                return Err(format!("`{key}` must be 1 to 86400000 (ms), not {v}"));
            }
            Ok(Duration::from_millis(v as u64))
        };
        let backoff = ms("restart_backoff_ms", 500)?;
        let max_backoff = ms("max_backoff_ms", 30_000)?;
        if max_backoff < backoff {
            return Err("`max_backoff_ms` must be at least `restart_backoff_ms`".into());
        }
        let connect = spec.str_or("connect", "").map_err(|e| e.to_string())?;
        Ok(ProcessModule { command, connect, backoff, max_backoff, sup: None })
    }
}

/// Whether `program` can be started: a path (with a `/`, as the process will be started
/// with it) is taken as given; a bare name must be an executable file in one of PATH's folders.
fn on_path(program: &str) -> bool {
    use std::os::unix::fs::PermissionsExt;
    if program.contains('/') {
        return true;
    }
    let Some(path) = std::env::var_os("PATH") else { return true };
    std::env::split_paths(&path).any(|dir| {
        std::fs::metadata(dir.join(program))
            .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
    })
}

impl Module for ProcessModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let _ = ctx.ds.set(ctx.status, "command", Value::str(&self.command.join(" ")));
        let _ = ctx.ds.set(ctx.status, "restarts", Value::Int(0));
        let _ = ctx.ds.set(ctx.status, "last_exit", Value::str(""));
        if self.connect.is_empty() {
            ctx.report(
                Level::Warning,
                "no Zenoh endpoint to hand the command (MOCU_CONNECT): the OCU does not listen",
            );
        }
        let sup = Arc::new(Supervisor {
            ctx: ctx.clone(),
            command: self.command.clone(),
            connect: self.connect.clone(),
            backoff: self.backoff,
            max_backoff: self.max_backoff,
            state: Mutex::new(State {
                stopping: false,
                kill: None,
                watcher: None,
                starts: 0,
                next: self.backoff,
            }),
        });
        sup.launch();
        self.sup = Some(sup);
        Ok(())
    }

    fn stop(&mut self) {
        let Some(sup) = self.sup.take() else { return };
        let (kill, watcher) = {
            let mut st = sup.state.lock();
            st.stopping = true;
            (st.kill.take(), st.watcher.take())
        };
        if let Some(k) = kill {
            let _ = k.send(());
        }
        if let Some(w) = watcher {
            let _ = w.join();
        }
        sup.set("state", Value::str("stopped"));
    }
}

impl Supervisor {
    fn set(&self, key: &str, v: Value) {
        let _ = self.ctx.ds.set(self.ctx.status, key, v);
    }

    /// Starts the command once; on failure, schedules the next try.
    fn launch(self: &Arc<Self>) {
        let mut st = self.state.lock();
        if st.stopping {
            return;
        }
        st.starts += 1;
        let restarts = st.starts - 1;
        self.set("restarts", Value::Int(restarts));
        self.set("next_start_in_ms", Value::Int(0));
        let mut cmd = Command::new(&self.command[0]);
        cmd.args(&self.command[1..]).stdin(Stdio::null());
        if !self.connect.is_empty() {
            cmd.env("MOCU_CONNECT", &self.connect);
        }
        cmd.env("MOCU_MODULE", &*self.ctx.name);
        if let Ok(fd) = std::io::stderr().as_fd().try_clone_to_owned() {
            if let Ok(fd2) = fd.try_clone() {
                cmd.stderr(Stdio::from(fd2));
            }
            cmd.stdout(Stdio::from(fd));
        }
        let what = self.command.join(" ");
        match cmd.spawn() {
            Ok(child) => {
                let pid = child.id();
                let verb = if restarts == 0 { "started" } else { "restarted" };
                self.ctx.report(Level::Info, format!("{verb} `{what}` (pid {pid})"));
                self.set("pid", Value::Int(pid as i64));
                self.set("state", Value::str("running"));
                let (tx, rx) = crossbeam_channel::bounded(1);
                st.kill = Some(tx);
                let me = self.clone();
                let started = self.ctx.ds.now();
                let watcher = std::thread::Builder::new()
                    .name(format!("{}-process", self.ctx.name))
                    .spawn(move || me.watch(child, rx, started));
                match watcher {
                    Ok(h) => st.watcher = Some(h),
                    Err(e) => self.ctx.report(Level::Error, format!("no watcher thread: {e}")),
                }
            }
            Err(e) => {
                self.ctx.report(Level::Error, format!("cannot start `{what}`: {e}"));
                self.set("state", Value::str("failed_to_start"));
                self.set("last_exit", Value::str(&format!("cannot start: {e}")));
                let delay = self.next_delay(&mut st, None);
                drop(st);
                self.schedule(delay);
            }
        }
    }

    /// Waits for the child to exit (or for `stop`, which kills it), then schedules the
    /// restart.
    fn watch(self: Arc<Self>, mut child: Child, kill: Receiver<()>, started: Instant) {
        let status = loop {
            match child.try_wait() {
                Ok(Some(s)) => break Some(s),
                Ok(None) => {}
                Err(_) => break None,
            }
            match kill.recv_timeout(POLL) {
                Err(RecvTimeoutError::Timeout) => {}
                Ok(()) | Err(RecvTimeoutError::Disconnected) => {
                    let _ = child.kill();
                    let _ = child.wait();
                    return;
                }
            }
        };
        let exit = status.map_or_else(|| "unknown".to_string(), describe);
        let mut st = self.state.lock();
        st.kill = None;
        if st.stopping {
            return;
        }
        let ran = self.ctx.ds.now().saturating_duration_since(started);
        let delay = self.next_delay(&mut st, Some(ran));
        drop(st);
        self.ctx.report(
            Level::Warning,
            format!(
                "`{}` exited ({exit}); restarting in {} ms",
                self.command.join(" "),
                delay.as_millis()
            ),
        );
        self.set("state", Value::str("down"));
        self.set("last_exit", Value::str(&exit));
        self.schedule(delay);
    }

    /// The back-off before the next start, and the one after it (doubled, capped). A run
    /// that lasted at least the cap starts the sequence again.
    fn next_delay(&self, st: &mut State, ran: Option<Duration>) -> Duration {
        if ran.is_some_and(|r| r >= self.max_backoff) {
            st.next = self.backoff;
        }
        let delay = st.next;
        st.next = (st.next * 2).min(self.max_backoff);
        delay
    }

    fn schedule(self: &Arc<Self>, delay: Duration) {
        self.set("next_start_in_ms", Value::Int(delay.as_millis() as i64));
        let me = self.clone();
        self.ctx.ds.run_after(delay, Some(&self.ctx.executor), move || me.launch());
    }
}

/// `exit 3`, `signal 9`.
fn describe(s: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (s.code(), s.signal()) {
        (Some(c), _) => format!("exit {c}"),
        (None, Some(sig)) => format!("signal {sig}"),
        _ => s.to_string(),
    }
}
