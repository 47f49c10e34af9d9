//! Incremental (re)loading. A program is a list of top-level items — windows, widgets,
//! watches, templates, the bindings — each compared with the running one by its definition
//! (source positions ignored). Unchanged items keep everything; only the others are
//! compiled, republished or torn down. Loading is reloading from nothing.

use crate::actions;
use crate::graph::{
    Builder, CompiledWidget, CompiledWindow, Frame, LoadError, Shared, State, compile_template,
    compile_widget, compile_window,
};
use mocu_language::program::Program;
use mocu_value::{Guid, Value};
use std::sync::Arc;

/// What a reload did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReloadStats {
    pub kept: usize,
    pub added: usize,
    pub changed: usize,
    pub removed: usize,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum ItemKey {
    Window(String),
    Widget(String, String),
    Watch(String),
    Template(String),
    Bindings,
}

/// A live top-level item: what it made.
pub(crate) struct ItemRec {
    key: ItemKey,
    canon: String,
    objects: Vec<Guid>,
    cells: Vec<usize>,
    watches: Vec<usize>,
    template: Option<usize>,
}

/// A definition as text with its source positions taken out: equal texts, same behaviour.
fn canon<T: serde::Serialize>(item: &T) -> String {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.remove("span");
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v = serde_json::to_value(item).unwrap_or(serde_json::Value::Null);
    strip(&mut v);
    v.to_string()
}

enum Def<'a> {
    Window(&'a mocu_language::program::Window),
    Widget(usize, &'a mocu_language::program::Widget),
    Watch(&'a mocu_language::program::Watch),
    Template(&'a mocu_language::program::Template),
    Bindings,
}

fn items(program: &Program) -> Vec<(ItemKey, String, Def<'_>)> {
    let mut out = Vec::new();
    // A changed design changes every placed item; a widget measured from its window's far
    // edge changes with the window.
    let design = format!("{:?}", program.design);
    for w in &program.windows {
        out.push((
            ItemKey::Window(w.name.clone()),
            design.clone() + canon(w).as_str(),
            Def::Window(w),
        ));
    }
    for (i, w) in program.widgets.iter().enumerate() {
        let name = w.name.clone().unwrap_or_else(|| format!("{}#{i}", w.component));
        let mut text = design.clone() + canon(w).as_str();
        if !w.anchor.is_default()
            && let Some(win) = program.windows.iter().find(|x| x.name == w.window)
        {
            text += canon(&win.rect).as_str();
        }
        out.push((ItemKey::Widget(w.window.clone(), name), text, Def::Widget(i, w)));
    }
    for w in &program.watches {
        out.push((ItemKey::Watch(w.name.clone()), canon(w), Def::Watch(w)));
    }
    for t in &program.templates {
        let key = format!("{}@{}", t.var, t.source);
        out.push((ItemKey::Template(key), design.clone() + canon(t).as_str(), Def::Template(t)));
    }
    out.push((ItemKey::Bindings, canon(&program.bindings), Def::Bindings));
    out
}

enum Compiled {
    Window(CompiledWindow),
    Widget(usize, CompiledWidget),
    Watch(crate::watch::CompiledWatch),
    Template(Box<crate::graph::TemplateRt>),
    Bindings(Vec<(String, Vec<actions::CompiledAction>)>),
}

impl Shared {
    /// Makes the running items those of `program`. Compiles first: a program that does not
    /// compile changes nothing.
    pub(crate) fn apply(
        self: &Arc<Self>,
        st: &mut State,
        program: &Program,
    ) -> Result<ReloadStats, LoadError> {
        let screen = self.config.screen;
        let frame = Frame::of(program, screen);
        let _ = self.ds.set(st.display, "scale", Value::Float(frame.scale));
        let lower = |e: crate::lower::LowerError| LoadError::Lower(e.to_string());
        let new = items(program);
        // 1. Compile what is new or changed (one compilation for all of it).
        let mut b = Builder::sharing(program);
        let mut todo: Vec<(ItemKey, String, Compiled)> = Vec::new();
        let mut stats = ReloadStats::default();
        for (key, text, def) in &new {
            if st.items.iter().any(|r| &r.key == key && &r.canon == text) {
                stats.kept += 1;
                continue;
            }
            let c = match def {
                Def::Window(w) => Compiled::Window(compile_window(&mut b, w, frame)?),
                Def::Widget(i, w) => {
                    let win = program.windows.iter().find(|x| x.name == w.window);
                    Compiled::Widget(*i, compile_widget(&mut b, w, *i, frame, win)?)
                }
                Def::Watch(w) => Compiled::Watch(crate::watch::compile_watch(&mut b, w, screen)?),
                Def::Template(t) => {
                    let t = compile_template(&mut b, t, frame, &program.windows)?;
                    Compiled::Template(Box::new(t))
                }
                Def::Bindings => {
                    let mut list = Vec::new();
                    for bind in &program.bindings {
                        let acts = actions::compile_actions(&mut b, &bind.actions, screen)
                            .map_err(lower)?;
                        list.push((actions::binding_key(bind), acts));
                    }
                    list.extend(crate::alerts::builtin_bindings(program));
                    Compiled::Bindings(list)
                }
            };
            todo.push((key.clone(), text.clone(), c));
        }
        let ir_nodes = b.ir_nodes;
        b.finish(self.config.jit)?;
        st.ir_nodes += ir_nodes;

        // 2. Tear down what went or changed. A changed window keeps its object (and so the
        //    widgets in it); a removed window takes its widgets with it.
        let new_keys: Vec<&ItemKey> = new.iter().map(|(k, _, _)| k).collect();
        let old_keys: Vec<ItemKey> = st.items.iter().map(|r| r.key.clone()).collect();
        let changed = |k: &ItemKey| todo.iter().any(|(t, _, _)| t == k);
        let mut keep = Vec::new();
        let mut kept_windows: Vec<(String, Guid)> = Vec::new();
        let old = std::mem::take(&mut st.items);
        let removed_windows: Vec<String> = old
            .iter()
            .filter_map(|r| match &r.key {
                ItemKey::Window(n) if !new_keys.contains(&&r.key) => Some(n.clone()),
                _ => None,
            })
            .collect();
        for rec in old {
            let gone = !new_keys.contains(&&rec.key);
            let window_gone =
                matches!(&rec.key, ItemKey::Widget(w, _) if removed_windows.contains(w));
            if !gone && !changed(&rec.key) && !window_gone {
                keep.push(rec);
                continue;
            }
            if gone || window_gone {
                stats.removed += 1;
            } else {
                stats.changed += 1;
            }
            for c in &rec.cells {
                self.remove_cell(st, *c);
            }
            for w in &rec.watches {
                crate::watch::remove_watch(self, st, *w);
            }
            if let Some(t) = rec.template {
                self.stop_template(st, t);
            }
            match &rec.key {
                ItemKey::Window(name) if !gone => {
                    // Keep the object; its new cell is bound below.
                    if let Some(g) = rec.objects.first() {
                        kept_windows.push((name.clone(), *g));
                    }
                }
                ItemKey::Window(name) => {
                    st.windows.remove(name);
                    for o in &rec.objects {
                        let _ = self.ds.delete_object(*o);
                    }
                }
                ItemKey::Bindings => {
                    if let Ok(Some(b)) = self.ds.find_child(st.display, "bindings") {
                        let _ = self.ds.delete_object(b);
                    }
                }
                _ => {
                    for o in &rec.objects {
                        let _ = self.ds.delete_object(*o);
                    }
                }
            }
        }
        st.items = keep;

        // 3. Publish what is new or changed: windows first, so widgets find them.
        todo.sort_by_key(|(k, _, _)| match k {
            ItemKey::Window(_) => 0,
            ItemKey::Widget(..) => 1,
            _ => 2,
        });
        for (key, text, c) in todo {
            if !old_keys.contains(&key) {
                stats.added += 1;
            }
            let mut rec = ItemRec {
                key: key.clone(),
                canon: text,
                objects: vec![],
                cells: vec![],
                watches: vec![],
                template: None,
            };
            match c {
                Compiled::Window(w) => match kept_windows.iter().find(|(n, _)| *n == w.name) {
                    Some((_, g)) => {
                        let cell = self.rebind_window(st, *g, &w);
                        rec.objects.push(*g);
                        rec.cells.push(cell);
                    }
                    None => {
                        for (g, cell) in
                            self.publish_windows(st, std::slice::from_ref(&w), None, 0)?
                        {
                            rec.objects.push(g);
                            rec.cells.push(cell);
                        }
                    }
                },
                Compiled::Widget(i, w) => {
                    for (g, cell) in self.publish_widgets(st, std::slice::from_ref(&w), None, i)? {
                        rec.objects.push(g);
                        rec.cells.push(cell);
                    }
                }
                Compiled::Watch(w) => {
                    let idx = self.add_watch(st, w, None);
                    rec.watches.push(idx);
                }
                Compiled::Template(t) => {
                    st.templates.push(*t);
                    let idx = st.templates.len() - 1;
                    self.start_template(st, idx);
                    rec.template = Some(idx);
                }
                Compiled::Bindings(list) => {
                    st.bindings = list;
                    actions::publish_bindings(self, st);
                }
            }
            st.items.push(rec);
        }
        crate::menu::publish_menus(self, st, program);
        crate::alerts::ensure_layer(self, st, program);
        crate::clock::follow(self, program);
        // Declaration order decides stacking among equal layers.
        for (i, w) in program.windows.iter().enumerate() {
            if let Some(g) = st.windows.get(&w.name) {
                let _ = self.ds.set(*g, "order", Value::Int(i as i64));
            }
        }
        Ok(stats)
    }
}
