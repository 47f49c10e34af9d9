//! Method calls as Zenoh queries (docs/distribution.md, "Calls").
//!
//! Serving: a query on `mocu/<site>/call/<path>/<method>` calls the method of the shared
//! object at `<path>` and is answered with the full outcome. Forwarding: a mirrored
//! object's method sends such a query to its site and answers the local call with the
//! reply: accepted (with results), refused with the reason, failed, no such method or
//! object, or timed out when no answer came in time.
//!
//! One thread does the Zenoh side of both, so no DataServer worker or Zenoh task ever
//! blocks on the other.

use crate::arbiter::Screen;
use crate::keys::{self, Key};
use crate::payload;
use crossbeam_channel::{Receiver, Sender};
use mocu_dataserver::{CallOutcome, DataServer, Responder, Value};
use parking_lot::Mutex;
use std::sync::Arc;
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::query::Query;

pub(crate) enum CallJob {
    /// A query from another site, to be carried out here.
    Serve(Query),
    /// Its outcome, to be sent back.
    Answer(Query, CallOutcome),
    /// A local call of a mirrored method, to be sent to its site.
    Forward {
        key: String,
        args: Vec<Value>,
        responder: Responder,
    },
    Stop,
}

pub(crate) struct Calls {
    pub ds: DataServer,
    pub session: zenoh::Session,
    pub me: String,
    pub operator: String,
    pub share: Vec<Vec<String>>,
    pub timeout: Duration,
    pub tx: Sender<CallJob>,
    /// Control arbitration of the vehicles served here (`arbiter.rs`), if on.
    pub arbiter: Option<crate::arbiter::Arbiter>,
}

impl Calls {
    pub fn run(self, rx: Receiver<CallJob>) {
        for job in rx.iter() {
            match job {
                CallJob::Stop => break,
                CallJob::Serve(q) => self.serve(q),
                CallJob::Answer(q, outcome) => {
                    let key = q.key_expr().clone();
                    let _ = q.reply(key, payload::outcome(&outcome)).wait();
                }
                CallJob::Forward { key, args, responder } => self.forward(key, args, responder),
            }
        }
    }

    fn serve(&self, q: Query) {
        let reply_now = |q: Query, o: CallOutcome| {
            let key = q.key_expr().clone();
            let _ = q.reply(key, payload::outcome(&o)).wait();
        };
        let Some(Key::Call { site, path, method }) = keys::parse(q.key_expr().as_str()) else {
            return reply_now(q, CallOutcome::NoSuchObject);
        };
        let shared = self.share.iter().any(|s| path.starts_with(s));
        let segs: Vec<&str> = path.iter().map(String::as_str).collect();
        let guid = if site == self.me && shared { self.ds.resolve(&segs) } else { None };
        let Some(guid) = guid else { return reply_now(q, CallOutcome::NoSuchObject) };
        let req = match payload::call_from(
            &q.payload().map(|p| p.to_bytes().into_owned()).unwrap_or_default(),
        ) {
            Ok(r) => r,
            Err(e) => return reply_now(q, CallOutcome::Failed(format!("malformed call: {}", e.0))),
        };
        if method == mocu_dataserver::WRITE_AT_OWNER {
            let outcome = crate::writes::serve(&self.ds, self.arbiter.as_ref(), guid, &path, req);
            return reply_now(q, outcome);
        }
        let defaults = self
            .ds
            .methods(guid)
            .unwrap_or_default()
            .into_iter()
            .find(|m| m.name.as_str() == method)
            .map(|m| m.defaults);
        let Some(mut options) = defaults else { return reply_now(q, CallOutcome::NoSuchMethod) };
        let t = req.timeout_ms.map_or(self.timeout, Duration::from_millis);
        if let Some(a) = &self.arbiter {
            let who = crate::control::Caller::new(
                req.operator.as_deref().unwrap_or(""),
                req.site.as_deref().unwrap_or(""),
            );
            match a.screen(&path, &method, &who) {
                Screen::Pass => {}
                Screen::Refuse(reason) => return reply_now(q, CallOutcome::Refused(reason)),
                Screen::Arbitrate(vehicle) => {
                    let tx = self.tx.clone();
                    let answer = Box::new(move |o| drop(tx.send(CallJob::Answer(q, o))));
                    return a.arbitrate(&vehicle, &method, &req.args, who, Some(t), answer);
                }
            }
        }
        options.timeout = Some(options.timeout.map_or(t, |d| d.min(t)));
        let tx = self.tx.clone();
        self.ds.call(guid, method.as_str(), req.args, Some(options), move |o| {
            let _ = tx.send(CallJob::Answer(q, o));
        });
    }

    fn forward(&self, key: String, args: Vec<Value>, responder: Responder) {
        let t = self.timeout;
        let slot = Arc::new(Mutex::new(Some(responder)));
        let guard = Unanswered { slot: slot.clone(), started: Instant::now(), timeout: t };
        let body = payload::call(&args, t.as_millis() as u64, &self.operator, &self.me);
        let sent = self
            .session
            .get(&key)
            .payload(body)
            // The site answers TimedOut at `t`; the extra second carries that answer back.
            .timeout(t + Duration::from_secs(1))
            .callback(move |reply| {
                let _keep = &guard;
                let outcome = match reply.result() {
                    Ok(s) => payload::outcome_from(&s.payload().to_bytes()).unwrap_or_else(|e| {
                        CallOutcome::Failed(format!("malformed answer: {}", e.0))
                    }),
                    Err(e) => CallOutcome::Failed(
                        e.payload().try_to_string().map(|s| s.into_owned()).unwrap_or_default(),
                    ),
                };
                let responder = slot.lock().take();
                if let Some(r) = responder {
                    r.reply(outcome);
                }
            })
            .wait();
        if let Err(e) = sent {
            // The guard went with the closure and answered; nothing else to do.
            let _ = e;
        }
    }
}

/// Answers a forwarded call nobody replied to when the query ends.
struct Unanswered {
    slot: Arc<Mutex<Option<Responder>>>,
    started: Instant,
    timeout: Duration,
}

impl Drop for Unanswered {
    fn drop(&mut self) {
        let responder = self.slot.lock().take();
        if let Some(r) = responder {
            let outcome = if self.started.elapsed() >= self.timeout {
                CallOutcome::TimedOut
            } else {
                CallOutcome::Failed("no site answers this method (its adapter is gone, or its access control denies this operator)".into())
            };
            r.reply(outcome);
        }
    }
}
