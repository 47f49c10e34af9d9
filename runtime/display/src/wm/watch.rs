//! Following the world model: windows as they appear under `root.display` and change, and
//! their `invalidate` method.

use super::*;

pub(super) fn on_child(
    ds: &DataServer,
    exec: &Executor,
    sh: &Arc<Shared>,
    subs: &Arc<Mutex<Vec<SubscriptionId>>>,
    n: &Notification,
) {
    let (guid, name, kind) = match &n.subject {
        Subject::Child { guid, name, kind, .. } => (*guid, name.clone(), kind.clone()),
        Subject::Object => {
            // root.display itself was deleted: every window goes.
            let mut st = sh.state.lock();
            let gone: Vec<Guid> = st.windows.keys().copied().collect();
            st.windows.clear();
            st.removed.extend(gone);
            sh.changed(&mut st);
            return;
        }
        Subject::Property { .. } => return,
    };
    let is_window = &*kind == WINDOW_TYPE;
    let known = sh.state.lock().windows.contains_key(&guid);
    match n.kind {
        Kind::New | Kind::Changed if is_window && !known => {
            let subtype = ds.info(guid).map(|i| i.subtype).unwrap_or_else(|_| "".into());
            let mut props = WinProps::new(name, subtype);
            for (p, v) in ds.properties(guid).unwrap_or_default() {
                apply_prop(&mut props, p.as_str(), Some(&v));
            }
            {
                let mut st = sh.state.lock();
                st.windows.insert(
                    guid,
                    WinEntry { props, sub: None, repaint: true, damage: IRect::default() },
                );
                st.reindex = true;
                sh.changed(&mut st);
            }
            publish_invalidate(ds, guid, sh);
            let sh2 = sh.clone();
            let sub = ds.subscribe_on(exec, Topic::properties(guid), move |n| {
                let Some(name) = n.property_name() else { return };
                let mut st = sh2.state.lock();
                let Some(e) = st.windows.get_mut(&guid) else { return };
                let effect = apply_prop(&mut e.props, name.as_str(), n.value());
                if n.kind == Kind::New && effect == Effect::None {
                    return;
                }
                match effect {
                    Effect::None => return,
                    Effect::Recomposite => {}
                    Effect::Repaint => e.repaint = true,
                }
                sh2.changed(&mut st);
            });
            if let Ok(sub) = sub {
                subs.lock().push(sub);
                if let Some(e) = sh.state.lock().windows.get_mut(&guid) {
                    e.sub = Some(sub);
                }
            }
        }
        Kind::Changed if is_window => {
            let subtype = ds.info(guid).map(|i| i.subtype).unwrap_or_else(|_| "".into());
            let mut st = sh.state.lock();
            if let Some(e) = st.windows.get_mut(&guid) {
                e.props.name = name;
                e.props.subtype = subtype;
                e.repaint = true;
            }
            sh.changed(&mut st);
        }
        Kind::New => {}
        Kind::Changed | Kind::Deleted => {
            let sub = {
                let mut st = sh.state.lock();
                let Some(e) = st.windows.remove(&guid) else { return };
                st.removed.push(guid);
                st.reindex = true;
                sh.changed(&mut st);
                e.sub
            };
            // Ended with no lock held: the window's property callback takes `state`.
            if let Some(s) = sub {
                subs.lock().retain(|x| *x != s);
                ds.unsubscribe(s);
            }
        }
    }
}

fn publish_invalidate(ds: &DataServer, window: Guid, sh: &Arc<Shared>) {
    let sh = sh.clone();
    let spec = MethodSpec::new("invalidate")
        .param(ParamSpec::new("x", ValueKind::Float))
        .param(ParamSpec::new("y", ValueKind::Float))
        .param(ParamSpec::new("w", ValueKind::Float))
        .param(ParamSpec::new("h", ValueKind::Float))
        .defaults(CallOptions::immediate())
        .describe("Marks a window-local rectangle of the window for repainting at the next frame");
    let _ = ds.publish_method_fn(window, spec, move |a| {
        let r = IRect::covering(crate::geom::Rect::new(
            arg_f(&a[0]) as f32,
            arg_f(&a[1]) as f32,
            arg_f(&a[2]) as f32,
            arg_f(&a[3]) as f32,
        ));
        let mut st = sh.state.lock();
        let Some(e) = st.windows.get_mut(&window) else {
            return CallOutcome::Failed("not a managed window".into());
        };
        e.damage = e.damage.union(&r);
        sh.changed(&mut st);
        CallOutcome::Accepted(vec![])
    });
}
