//! Publishing compiled windows and widgets under `root.display`, and templates: one
//! instance per object of the source (`for each`), created, reindexed and removed as the
//! source's children come and go.

use super::compile::WINDOW_OUTPUTS;
use super::{
    CompiledWidget, CompiledWindow, InboxEvent, LoadError, Shared, Start, State, Target, mark,
};
use crate::actions;
use crate::lower::Base;
use mocu_dataserver::{Kind, ObjectInfo, PathEvent, PathWatch, Subject, Topic};
use mocu_value::{Guid, PropName, Value};
use std::sync::Arc;

/// One template's compiled pieces, instantiated per matching object.
pub(crate) struct TemplateRt {
    pub(crate) alive: bool,
    pub(crate) source: Vec<String>,
    pub(crate) object_type: Option<String>,
    pub(crate) var: String,
    /// `flow …`: its windows placed by the runtime (`flow.rs`).
    pub(crate) flow: Option<super::flow::FlowRt>,
    pub(crate) windows: Vec<CompiledWindow>,
    pub(crate) widgets: Vec<CompiledWidget>,
    pub(crate) watches: Vec<crate::watch::CompiledWatch>,
    pub(crate) source_watch: Option<PathWatch>,
    pub(crate) source_object: Option<Guid>,
    pub(crate) children_sub: Option<mocu_dataserver::SubscriptionId>,
}

pub(crate) struct Instance {
    pub(crate) object: Guid,
    pub(crate) template: usize,
    pub(crate) index: usize,
    pub(crate) objects: Vec<Guid>,
    pub(crate) cells: Vec<usize>,
    pub(crate) watches: Vec<usize>,
    /// Its template flows: its windows' boxes, in order, go to the flow (`flow.rs`).
    pub(crate) flowed: bool,
    pub(crate) boxes: Vec<super::flow::FlowBox>,
}

impl Shared {
    /// Template instances name their objects `name@object`.
    pub(crate) fn instance_suffix(&self, st: &State, instance: Option<usize>) -> Option<String> {
        instance
            .and_then(|i| st.instances[i].as_ref())
            .map(|i| self.ds.info(i.object).map(|inf| inf.name.to_string()).unwrap_or_default())
    }

    /// The dotted-path text of an object path from a base (`root.vehicles.usv1.cameras.drive`).
    pub(crate) fn path_from(
        &self,
        st: &State,
        base: &Base,
        objs: &[String],
        instance: Option<usize>,
    ) -> String {
        match Self::start_of(st, base, instance) {
            Some(Start::Object(o)) => format!("{}.{}", self.ds.path_text(o), objs.join(".")),
            _ => format!("root.{}", objs.join(".")),
        }
    }

    pub(crate) fn publish_windows(
        self: &Arc<Self>,
        st: &mut State,
        windows: &[CompiledWindow],
        instance: Option<usize>,
        first_order: usize,
    ) -> Result<Vec<(Guid, usize)>, LoadError> {
        let mut made = Vec::new();
        let suffix = self.instance_suffix(st, instance);
        for (order, w) in (first_order + st.windows.len()..).zip(windows) {
            let name = match &suffix {
                Some(s) => format!("{}@{s}", w.name),
                None => w.name.clone(),
            };
            let kind = if w.kind == "layer" { "widgets" } else { w.kind.as_str() };
            let g = self
                .ds
                .create_object(st.display, ObjectInfo::new(&name, "window").subtype(kind))
                .map_err(|e| LoadError::World(e.to_string()))?;
            let _ = self.ds.set(g, "order", Value::Int(order as i64));
            let _ = self.ds.set(g, "revision", Value::Int(0));
            let _ = self.ds.set(g, "clip", Value::Bool(true));
            if let Some((base, objs)) = &w.source {
                let text = self.path_from(st, base, objs, instance);
                let _ = self.ds.set(g, "source", Value::str(&text));
            }
            let flowed = instance.and_then(|i| st.instances[i].as_mut()).filter(|x| x.flowed);
            let targets = match (flowed, instance) {
                (Some(inst), Some(i)) => {
                    inst.boxes.push(super::flow::FlowBox::new(g));
                    super::flow::window_targets(g, i, inst.boxes.len() - 1)
                }
                _ => WINDOW_OUTPUTS.iter().map(|n| Target::Prop(g, PropName::new(n))).collect(),
            };
            let cell = self.add_cell(st, &w.f, targets, instance);
            made.push((g, cell));
            st.windows.insert(name.clone(), g);
            match instance {
                Some(i) => {
                    if let Some(inst) = st.instances[i].as_mut() {
                        inst.objects.push(g);
                        inst.cells.push(cell);
                    }
                }
                None => st.owned.push(g),
            }
        }
        Ok(made)
    }

    /// A changed top-level window keeps its object (and the widgets in it): new kind,
    /// source and cell.
    pub(crate) fn rebind_window(
        self: &Arc<Self>,
        st: &mut State,
        g: Guid,
        w: &CompiledWindow,
    ) -> usize {
        let kind = if w.kind == "layer" { "widgets" } else { w.kind.as_str() };
        if let Ok(info) = self.ds.info(g)
            && &*info.subtype != kind
        {
            let _ = self.ds.set_info(g, ObjectInfo::new(&info.name, "window").subtype(kind));
        }
        match &w.source {
            Some((_, objs)) => {
                let _ = self.ds.set(g, "source", Value::str(&format!("root.{}", objs.join("."))));
            }
            None => {
                let _ = self.ds.delete_property(g, "source");
            }
        }
        let targets = WINDOW_OUTPUTS.iter().map(|n| Target::Prop(g, PropName::new(n))).collect();
        self.add_cell(st, &w.f, targets, None)
    }

    pub(crate) fn publish_widgets(
        self: &Arc<Self>,
        st: &mut State,
        widgets: &[CompiledWidget],
        instance: Option<usize>,
        first_order: usize,
    ) -> Result<Vec<(Guid, usize)>, LoadError> {
        let mut made = Vec::new();
        let suffix = self.instance_suffix(st, instance);
        for (i, w) in widgets.iter().enumerate() {
            let order = first_order + i;
            let window_name = match &suffix {
                Some(s) if st.windows.contains_key(&format!("{}@{s}", w.window)) => {
                    format!("{}@{s}", w.window)
                }
                _ => w.window.clone(),
            };
            let Some(&win) = st.windows.get(&window_name) else {
                return Err(LoadError::World(format!(
                    "widget `{}` is in unknown window `{}`",
                    w.name, w.window
                )));
            };
            let name = match &suffix {
                Some(s) => format!("{}@{s}", w.name),
                None => w.name.clone(),
            };
            let g = self
                .ds
                .create_object(win, ObjectInfo::new(&name, "widget").subtype(&w.component))
                .map_err(|e| LoadError::World(e.to_string()))?;
            let _ = self.ds.set(g, "component", Value::str(&w.component));
            let _ = self.ds.set(g, "native", Value::Bool(w.native));
            if w.scale != 1.0 {
                let _ = self.ds.set(g, "scale", Value::Float(w.scale));
            }
            let _ = self.ds.set(g, "order", Value::Int(order as i64));
            for (arg, base, objs) in &w.objects {
                let text = self.path_from(st, base, objs, instance);
                let _ = self.ds.set(g, arg.as_str(), Value::str(&text));
            }
            let targets = w.outputs.iter().map(|n| Target::Prop(g, PropName::new(n))).collect();
            let cell = self.add_cell(st, &w.f, targets, instance);
            made.push((g, cell));
            let object = instance.and_then(|i| st.instances[i].as_ref()).map(|i| i.object);
            crate::stale::register(self, g, &w.data_through, object);
            actions::publish_handlers(self, g, &w.handlers, object);
            if let Some(i) = instance
                && let Some(inst) = st.instances[i].as_mut()
            {
                inst.cells.push(cell);
            }
        }
        Ok(made)
    }

    pub(crate) fn add_watch(
        self: &Arc<Self>,
        st: &mut State,
        w: crate::watch::CompiledWatch,
        instance: Option<usize>,
    ) -> usize {
        let idx = crate::watch::publish_watch(self, st, w, instance);
        if let Some(i) = instance
            && let Some(inst) = st.instances[i].as_mut()
        {
            inst.watches.push(idx);
        }
        idx
    }

    /// Starts following template `t`'s source object.
    pub(crate) fn start_template(self: &Arc<Self>, st: &mut State, t: usize) {
        let objs: Vec<&str> = st.templates[t].source.iter().map(|s| s.as_str()).collect();
        let weak = self.weak();
        let watch =
            self.ds.watch_object(Guid::ROOT, &objs, Some(&self.exec), move |e: &PathEvent| {
                if let Some(sh) = weak.upgrade() {
                    let obj = (e.kind != Kind::Deleted).then_some(e.object);
                    sh.post(InboxEvent::TemplateSource(t, obj));
                }
            });
        st.templates[t].source_watch = watch.ok();
        self.start_flow(st, t);
    }

    /// Ends template `t`: its instances go, it follows nothing any more.
    pub(crate) fn stop_template(self: &Arc<Self>, st: &mut State, t: usize) {
        st.templates[t].alive = false;
        st.templates[t].source_watch = None;
        if let Some(id) = st.templates[t].children_sub.take() {
            self.ds.unsubscribe(id);
        }
        let old: Vec<usize> = (0..st.instances.len())
            .filter(|&i| st.instances[i].as_ref().is_some_and(|x| x.template == t))
            .collect();
        for i in old {
            self.remove_instance(st, i);
        }
        self.stop_flow(st, t);
    }

    pub(crate) fn template_source(self: &Arc<Self>, st: &mut State, t: usize, obj: Option<Guid>) {
        if let Some(id) = st.templates[t].children_sub.take() {
            self.ds.unsubscribe(id);
        }
        // Every instance of the old source goes.
        let old: Vec<usize> = (0..st.instances.len())
            .filter(|&i| st.instances[i].as_ref().is_some_and(|x| x.template == t))
            .collect();
        for i in old {
            self.remove_instance(st, i);
        }
        st.templates[t].source_object = obj;
        if let Some(obj) = obj {
            let weak = self.weak();
            let sub = self.ds.subscribe_on(&self.exec, Topic::children(obj), move |n| {
                if let (Some(sh), Subject::Child { guid, kind, .. }) = (weak.upgrade(), &n.subject)
                {
                    sh.post(InboxEvent::TemplateChild(t, n.kind, *guid, kind.clone()));
                }
            });
            st.templates[t].children_sub = sub.ok();
        }
    }

    pub(crate) fn template_child(
        self: &Arc<Self>,
        st: &mut State,
        t: usize,
        kind: Kind,
        g: Guid,
        ty: &str,
    ) {
        let existing = st
            .instances
            .iter()
            .position(|i| i.as_ref().is_some_and(|i| i.template == t && i.object == g));
        match kind {
            Kind::Deleted => {
                if let Some(i) = existing {
                    self.remove_instance(st, i);
                    self.reindex(st, t);
                }
            }
            Kind::New | Kind::Changed => {
                let wanted = st.templates[t].object_type.as_deref().is_none_or(|w| w == ty);
                match (existing, wanted) {
                    (None, true) => {
                        self.add_instance(st, t, g);
                        self.reindex(st, t);
                    }
                    (Some(i), false) => {
                        self.remove_instance(st, i);
                        self.reindex(st, t);
                    }
                    _ => {}
                }
            }
        }
    }

    pub(crate) fn add_instance(self: &Arc<Self>, st: &mut State, t: usize, object: Guid) {
        let idx = st.instances.len();
        st.instances.push(Some(Instance {
            object,
            template: t,
            index: 0,
            objects: vec![],
            cells: vec![],
            watches: vec![],
            flowed: st.templates[t].flow.is_some(),
            boxes: vec![],
        }));
        let tpl = std::mem::replace(
            &mut st.templates[t],
            TemplateRt {
                alive: true,
                source: vec![],
                object_type: None,
                var: String::new(),
                flow: None,
                windows: vec![],
                widgets: vec![],
                watches: vec![],
                source_watch: None,
                source_object: None,
                children_sub: None,
            },
        );
        let r = self
            .publish_windows(st, &tpl.windows, Some(idx), 1000)
            .and_then(|_| self.publish_widgets(st, &tpl.widgets, Some(idx), 0));
        if let Err(e) = r {
            self.sink.record("diagnostic", &[("message", Value::str(&e.to_string()))]);
        }
        for w in &tpl.watches {
            self.add_watch(st, w.clone(), Some(idx));
        }
        self.sink.record(
            "instance",
            &[
                ("template", Value::str(&tpl.var)),
                ("object", Value::str(&self.ds.path_text(object))),
            ],
        );
        st.templates[t] = tpl;
    }

    pub(crate) fn remove_instance(self: &Arc<Self>, st: &mut State, i: usize) {
        let Some(inst) = st.instances[i].take() else { return };
        super::flow::mark(st, inst.template);
        for c in inst.cells {
            self.remove_cell(st, c);
        }
        for w in inst.watches {
            crate::watch::remove_watch(self, st, w);
        }
        st.windows.retain(|_, g| !inst.objects.contains(g));
        for o in inst.objects {
            let _ = self.ds.delete_object(o);
        }
    }

    /// Instance indexes follow the order of the source's children.
    pub(crate) fn reindex(self: &Arc<Self>, st: &mut State, t: usize) {
        super::flow::mark(st, t); // instances came, went or moved: placed again
        let Some(src) = st.templates[t].source_object else { return };
        let order = self.ds.children(src).unwrap_or_default();
        let mut mine: Vec<usize> = (0..st.instances.len())
            .filter(|&i| st.instances[i].as_ref().is_some_and(|x| x.template == t))
            .collect();
        mine.sort_by_key(|&i| {
            let o = st.instances[i].as_ref().map(|x| x.object);
            order.iter().position(|c| Some(*c) == o).unwrap_or(usize::MAX)
        });
        for (n, i) in mine.into_iter().enumerate() {
            let cells = match st.instances[i].as_mut() {
                Some(inst) if inst.index != n => {
                    inst.index = n;
                    inst.cells.clone()
                }
                _ => continue,
            };
            for c in cells {
                mark(st, c);
            }
        }
    }
}
