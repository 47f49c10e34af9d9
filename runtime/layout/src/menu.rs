//! Context menus at run time: each `menu for type "T" { item … }` of the program becomes
//! an object `root.display.menus.T` (type `menu`, `items` = how many) with two methods,
//! so that whatever module shows the menu (the widget renderer on a right-click on a
//! vehicle in a map or a vehicle list) needs no layout:
//!
//! - `open(object: string)` — `object` is a dotted path (`root.vehicles.usv1`) bound to
//!   `self`; answers `[label1, enabled1, label2, enabled2, …]` evaluated now;
//! - `choose(index: int, object: string)` — runs item `index`'s actions with `self` bound
//!   (refused when the item is disabled now, or the object is gone).
//!
//! Published anew on every load and reload (its own compilation); unloading the layout
//! removes them with the layout's other objects.

use crate::actions::{ActionCtx, CompiledAction, compile_actions, run_actions};
use crate::graph::{Builder, FnRef, Shared, State, ensure_object, eval_once};
use crate::lower::{Lowerer, Scope};
use mocu_dataserver::{CallOutcome, DataServer, MethodSpec, ObjectInfo, ParamSpec};
use mocu_jit as jit;
use mocu_language::program::Program;
use mocu_value::{Guid, Value, ValueKind};
use std::sync::Arc;

struct Item {
    label: FnRef,
    enabled: Option<FnRef>,
    actions: Vec<CompiledAction>,
}

/// Resolves `root.a.b` (or `a.b`) to an object.
fn object_at(ds: &DataServer, path: &str) -> Option<Guid> {
    let mut segs: Vec<&str> = path.split('.').filter(|s| !s.is_empty()).collect();
    if segs.first() == Some(&"root") {
        segs.remove(0);
    }
    if segs.is_empty() { None } else { ds.resolve(&segs) }
}

fn compile(
    program: &Program,
    screen: (f64, f64),
    use_jit: bool,
) -> Result<Vec<(String, Vec<Item>)>, String> {
    let mut b = Builder::new();
    let mut menus = Vec::new();
    for m in &program.menus {
        let mut items = Vec::new();
        for it in &m.items {
            let mut lw = Lowerer::new(Scope::Plain, screen);
            let e = lw.lower(&it.label.expr, jit::Ty::Str).map_err(|e| e.to_string())?;
            let label = b.add(lw, vec![e]);
            let enabled = match &it.enabled {
                Some(c) => {
                    let mut lw = Lowerer::new(Scope::Plain, screen);
                    let e = lw.lower(&c.expr, jit::Ty::Bool).map_err(|e| e.to_string())?;
                    Some(b.add(lw, vec![e]))
                }
                None => None,
            };
            let actions =
                compile_actions(&mut b, &it.actions, screen).map_err(|e| e.to_string())?;
            items.push(Item { label, enabled, actions });
        }
        menus.push((m.object_type.clone(), items));
    }
    b.finish(use_jit).map_err(|e| e.to_string())?;
    Ok(menus)
}

fn is_enabled(sh: &Shared, it: &Item, obj: Guid) -> bool {
    match &it.enabled {
        None => true,
        Some(f) => {
            eval_once(sh, f, None, Some(obj), None).first().cloned().flatten()
                == Some(Value::Bool(true))
        }
    }
}

/// (Re)publishes the program's menus under `root.display.menus`.
pub(crate) fn publish_menus(sh: &Arc<Shared>, st: &mut State, program: &Program) {
    let ds = &sh.ds;
    if let Ok(Some(old)) = ds.find_child(st.display, "menus") {
        let _ = ds.delete_object(old);
    }
    if program.menus.is_empty() {
        return;
    }
    let menus = match compile(program, sh.config.screen, sh.config.jit) {
        Ok(m) => m,
        Err(e) => {
            sh.sink.record("menu_error", &[("error", Value::str(&e))]);
            return;
        }
    };
    let Ok(folder) = ensure_object(ds, st.display, "menus", "menus") else { return };
    for (ty, items) in menus {
        let Ok(m) = ds.create_object(folder, ObjectInfo::new(&ty, "menu")) else { continue };
        let _ = ds.set(m, "items", Value::Int(items.len() as i64));
        let items = Arc::new(items);
        let (weak, its) = (Arc::downgrade(sh), items.clone());
        let open = MethodSpec::new("open")
            .param(ParamSpec::new("object", ValueKind::String))
            .describe("The items for an object: label, enabled, label, enabled, …");
        let _ = ds.publish_method_fn(m, open, move |args| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("the layout was unloaded".into());
            };
            let Some(obj) = args[0].as_str().and_then(|p| object_at(&sh.ds, p)) else {
                return CallOutcome::Refused("no such object".into());
            };
            let mut out = Vec::new();
            for it in its.iter() {
                let label = eval_once(&sh, &it.label, None, Some(obj), None)
                    .first()
                    .cloned()
                    .flatten()
                    .map(|v| v.to_string())
                    .unwrap_or_else(|| "—".into());
                out.push(Value::str(&label));
                out.push(Value::Bool(is_enabled(&sh, it, obj)));
            }
            CallOutcome::Accepted(out)
        });
        let (weak, its) = (Arc::downgrade(sh), items);
        let choose = MethodSpec::new("choose")
            .param(ParamSpec::new("index", ValueKind::Int))
            .param(ParamSpec::new("object", ValueKind::String))
            .describe("Runs an item's actions with `self` bound to the object");
        let _ = ds.publish_method_fn(m, choose, move |args| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("the layout was unloaded".into());
            };
            let Some(obj) = args[1].as_str().and_then(|p| object_at(&sh.ds, p)) else {
                return CallOutcome::Refused("no such object".into());
            };
            let Some(it) = args[0].as_i64().and_then(|i| its.get(usize::try_from(i).ok()?)) else {
                return CallOutcome::Refused("no such item".into());
            };
            if !is_enabled(&sh, it, obj) {
                return CallOutcome::Refused("item disabled".into());
            }
            let cx = ActionCtx { self_obj: Some(obj), ..ActionCtx::default() };
            run_actions(&sh, &it.actions, cx);
            CallOutcome::Accepted(vec![])
        });
    }
    st.owned_push(folder);
}
