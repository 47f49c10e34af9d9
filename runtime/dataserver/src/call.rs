//! Carrying out a method call: answering it exactly once, its timeout, and queued or
//! delayed calls that resolve their target when they run.
//!
//! - The timeout is a timer job that runs on the timer thread itself (never waiting for a
//!   worker); an answer releases it at once.
//! - A queued or delayed call looks its object and method up again when it runs: one
//!   deleted or unpublished meanwhile answers `NoSuchObject` / `NoSuchMethod`, and a call
//!   already answered (`TimedOut`) does not run at all.

use crate::executor::Target;
use crate::feed::Change;
use crate::method::{CallMode, CallOptions, CallOutcome, Method, check_args};
use crate::server::{DataServer, Inner};
use crate::timer::{Fire, TimerKey};
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Weak};
use std::time::Duration;

type Completion = Box<dyn FnOnce(CallOutcome) + Send + 'static>;

struct ReplySlot {
    state: Mutex<SlotState>,
    server: Weak<Inner>,
}

struct SlotState {
    done: Option<Completion>,
    timeout: Option<TimerKey>,
}

impl ReplySlot {
    fn finish(&self, outcome: CallOutcome) -> bool {
        let (done, timeout) = {
            let mut st = self.state.lock();
            (st.done.take(), st.timeout.take())
        };
        if let (Some(key), Some(inner)) = (timeout, self.server.upgrade()) {
            inner.timer.cancel(key);
        }
        match done {
            Some(f) => {
                f(outcome);
                true
            }
            None => false,
        }
    }

    fn answered(&self) -> bool {
        self.state.lock().done.is_none()
    }
}

/// The right to answer one call, once. Dropping it unanswered answers `Failed`.
pub struct Responder {
    slot: Option<Arc<ReplySlot>>,
}

impl Responder {
    /// Answers the call. Returns false when the call had already ended (timed out).
    pub fn reply(mut self, outcome: CallOutcome) -> bool {
        self.slot.take().is_some_and(|s| s.finish(outcome))
    }

    pub fn accept(self, results: Vec<Value>) -> bool {
        self.reply(CallOutcome::Accepted(results))
    }

    pub fn refuse(self, reason: impl Into<String>) -> bool {
        self.reply(CallOutcome::Refused(reason.into()))
    }

    pub fn fail(self, error: impl Into<String>) -> bool {
        self.reply(CallOutcome::Failed(error.into()))
    }

    /// Whether the call has already been answered (it timed out): a handler may skip work
    /// nobody waits for.
    pub fn is_answered(&self) -> bool {
        self.slot.as_ref().is_none_or(|s| s.answered())
    }
}

impl Drop for Responder {
    fn drop(&mut self) {
        if let Some(s) = self.slot.take() {
            s.finish(CallOutcome::Failed("the method's handler ended without answering".into()));
        }
    }
}

/// One call as its handler sees it.
pub struct Call {
    pub object: Guid,
    pub method: PropName,
    pub args: Arc<[Value]>,
    pub responder: Responder,
}

impl DataServer {
    /// Calls a method. `done` receives the outcome exactly once: on this thread for
    /// immediate calls and for calls that cannot start, on the timer thread for `TimedOut`
    /// (keep `done` short: it must not block), else where the handler answers.
    /// `options` overrides the method's default call options. A queued or delayed call
    /// resolves its object and method when it runs (see the module docs).
    pub fn call(
        &self,
        guid: Guid,
        name: impl Into<PropName>,
        args: Vec<Value>,
        options: Option<CallOptions>,
        done: impl FnOnce(CallOutcome) + Send + 'static,
    ) {
        let name = name.into();
        let done = self.recorded_call(guid, name, &args, done);
        self.call_unfed(guid, name, args, options, done)
    }

    /// [`DataServer::call`] without the change feed: a stream's delivery to each receiver
    /// (the message itself is fed once, when sent).
    pub(crate) fn call_unfed(
        &self,
        guid: Guid,
        name: PropName,
        args: Vec<Value>,
        options: Option<CallOptions>,
        done: impl FnOnce(CallOutcome) + Send + 'static,
    ) {
        let method = match self.resolve_method(guid, name) {
            Ok(m) => m,
            Err(outcome) => return done(outcome),
        };
        let args = match check_args(&method.spec, args) {
            Ok(a) => a,
            Err(why) => return done(CallOutcome::Failed(why)),
        };
        let options = options.unwrap_or(method.spec.defaults);
        let slot = Arc::new(ReplySlot {
            state: Mutex::new(SlotState { done: Some(Box::new(done)), timeout: None }),
            server: Arc::downgrade(&self.inner),
        });
        if let Some(t) = options.timeout {
            let s = slot.clone();
            let key = self.inner.timer.schedule(
                t,
                Fire::Inline,
                Box::new(move || {
                    s.finish(CallOutcome::TimedOut);
                }),
            );
            let mut st = slot.state.lock();
            match (st.done.is_some(), key) {
                (true, key) => st.timeout = key,
                (false, Some(key)) => {
                    drop(st);
                    self.inner.timer.cancel(key);
                }
                (false, None) => {}
            }
        }
        let call =
            Call { object: guid, method: name, args, responder: Responder { slot: Some(slot) } };
        if options.mode == CallMode::Immediate && options.delay.is_zero() {
            run_handler(&self.inner, &method, call);
            return;
        }
        let target = method.target(&self.inner.pool);
        let job = queued_job(Arc::downgrade(&self.inner), method, call);
        if options.delay.is_zero() {
            target.submit(job);
        } else {
            self.inner.timer.schedule(options.delay, Fire::Submit(target), job);
        }
    }

    /// `done`, answering also to the change feed when one is open: the call is numbered
    /// and fed now, its outcome when it is answered.
    fn recorded_call(
        &self,
        guid: Guid,
        method: PropName,
        args: &[Value],
        done: impl FnOnce(CallOutcome) + Send + 'static,
    ) -> Completion {
        if !self.inner.feeds.is_open() {
            return Box::new(done);
        }
        let call = self.inner.feeds.next_call();
        self.emit(|| Change::Called { call, object: guid, method, args: args.to_vec() });
        let server = Arc::downgrade(&self.inner);
        Box::new(move |outcome: CallOutcome| {
            if let Some(inner) = server.upgrade() {
                DataServer { inner }.emit(|| Change::Answered { call, outcome: outcome.clone() });
            }
            done(outcome)
        })
    }

    /// The method as published now, or why there is none.
    pub(crate) fn resolve_method(
        &self,
        guid: Guid,
        name: PropName,
    ) -> Result<Arc<Method>, CallOutcome> {
        let o = self.object(guid).map_err(|_| CallOutcome::NoSuchObject)?;
        let os = o.state.read();
        if !os.alive {
            return Err(CallOutcome::NoSuchObject);
        }
        os.methods.get(&name).cloned().ok_or(CallOutcome::NoSuchMethod)
    }

    /// Calls a method and waits for its outcome. Not for use on a serial executor that the
    /// method itself runs on (it would wait for itself). With a timeout it returns by then,
    /// whatever the workers are doing.
    pub fn call_wait(
        &self,
        guid: Guid,
        name: impl Into<PropName>,
        args: Vec<Value>,
        options: Option<CallOptions>,
    ) -> CallOutcome {
        let (tx, rx) = crossbeam_channel::bounded(1);
        self.call(guid, name, args, options, move |o| {
            let _ = tx.send(o);
        });
        rx.recv().unwrap_or(CallOutcome::Failed("the call was dropped".into()))
    }

    /// Runs `f` on `executor` (or any worker) after `delay` on the server's clock: how a
    /// module does periodic work without a thread of its own (re-arm from inside `f`). A
    /// delay too large for the clock is clamped to a hundred years.
    pub fn run_after(
        &self,
        delay: Duration,
        executor: Option<&crate::Executor>,
        f: impl FnOnce() + Send + 'static,
    ) {
        let target = match executor {
            Some(ex) => Target::Serial(ex.clone()),
            None => Target::Pool(self.inner.pool.clone()),
        };
        self.inner.timer.schedule(delay, Fire::Submit(target), Box::new(f));
    }
}

/// A queued call: when it runs, it is answered already (skip), or its object or method is
/// gone (answer so), or the method was published again (run that one, on its executor), or
/// it runs the handler it was queued for.
fn queued_job(server: Weak<Inner>, planned: Arc<Method>, call: Call) -> crate::executor::Job {
    Box::new(move || {
        if !call.responder.is_answered()
            && let Some(inner) = server.upgrade()
        {
            let ds = DataServer { inner };
            let now = match ds.resolve_method(call.object, call.method) {
                Ok(m) => m,
                Err(outcome) => {
                    call.responder.reply(outcome);
                    return;
                }
            };
            if Arc::ptr_eq(&now, &planned) {
                run_handler(&ds.inner, &now, call);
                return;
            }
            let Call { object, method, args, responder } = call;
            match check_args(&now.spec, args.to_vec()) {
                Err(why) => {
                    responder.reply(CallOutcome::Failed(why));
                }
                Ok(args) => {
                    let call = Call { object, method, args, responder };
                    let target = now.target(&ds.inner.pool);
                    if target.same(&planned.target(&ds.inner.pool)) {
                        // Already where it runs: now, in the order it was made (an ordered
                        // method published again keeps its executor).
                        run_handler(&ds.inner, &now, call);
                    } else {
                        target.submit(queued_job(Arc::downgrade(&ds.inner), now, call));
                    }
                }
            }
        }
    })
}

fn run_handler(inner: &Inner, method: &Method, call: Call) {
    // A panicking handler drops its responder while unwinding: the caller sees Failed, and
    // the OCU goes on. Counted like any other caught panic.
    if catch_unwind(AssertUnwindSafe(|| (method.handler)(call))).is_err() {
        inner.pool.stats.panics_caught.fetch_add(1, Ordering::Relaxed);
    }
}
