//! The context menu: a right-click on an object (a vehicle symbol in a map, a vehicle in
//! a list) asks the layout's menu for that object's type (`root.display.menus.<type>`,
//! published by the layout) for its items, and shows them in a window of their own on top
//! of everything (`root.display.context_menu`, subtype `widgets`, one native
//! `ContextMenu` widget). The widget renderer draws it and handles its pointer: hover
//! highlights a row, a left press on an enabled row runs `choose(index, object)` and
//! closes it, the pointer leaving it closes it.

use mocu_dataserver::{CallOutcome, DataServer};
use mocu_display::{Point, Rect};
use mocu_value::{Guid, PropName, Value};

/// The menu window's name under `root.display`.
pub const WINDOW: &str = "context_menu";
/// Height of a row and of the title, and the menu's width, in px.
pub const ROW: f32 = 26.0;
pub const TITLE: f32 = 26.0;
pub const WIDTH: f32 = 180.0;

/// Closes the context menu, if one is open.
pub fn close(ds: &DataServer) {
    if let Some(w) = ds.resolve(&["display", WINDOW]) {
        let _ = ds.delete_object(w);
    }
}

/// Opens the context menu of `object` with its top-left corner at screen point `at`.
/// Returns false when the layout has no menu for the object's type.
pub fn open(ds: &DataServer, object: Guid, at: Point) -> bool {
    close(ds);
    let Ok(info) = ds.info(object) else { return false };
    let Some(menu) = ds.resolve(&["display", "menus", &info.kind]) else { return false };
    let path = ds.path_text(object);
    let CallOutcome::Accepted(items) = ds.call_wait(menu, "open", vec![Value::str(&path)], None)
    else {
        return false;
    };
    let n = items.len() / 2;
    if n == 0 {
        return false;
    }
    let Some(display) = ds.resolve(&["display"]) else { return false };
    let num = |k: &str| ds.try_get(display, PropName::new(k)).and_then(|v| v.as_f64());
    let (sw, sh) = (num("width").unwrap_or(1920.0) as f32, num("height").unwrap_or(1080.0) as f32);
    let h = TITLE + ROW * n as f32 + 6.0;
    // Kept on the screen.
    let x = at.x.min(sw - WIDTH - 2.0).max(0.0);
    let y = at.y.min(sh - h - 2.0).max(0.0);
    let Ok(win) = mocu_display::publish_window(
        ds,
        display,
        WINDOW,
        "widgets",
        1000,
        Rect::new(x, y, WIDTH, h),
    ) else {
        return false;
    };
    let Ok(w) = ds.create_object(
        win,
        mocu_dataserver::ObjectInfo::new("menu", "widget").subtype("ContextMenu"),
    ) else {
        return false;
    };
    let _ = ds.set(w, "object", Value::str(&path));
    let _ = ds.set(w, "title", Value::str(&info.name.to_uppercase()));
    let _ = ds.set(w, "menu_type", Value::str(&info.kind));
    let _ = ds.set(w, "items", Value::Int(n as i64));
    for (i, pair) in items.chunks_exact(2).enumerate() {
        let _ = ds.set(w, format!("item{i}").as_str(), pair[0].clone());
        let _ = ds.set(w, format!("enabled{i}").as_str(), pair[1].clone());
    }
    let _ = ds.set(w, "hover_row", Value::Int(-1));
    let _ = ds.set(w, "x", Value::Float(0.0));
    let _ = ds.set(w, "y", Value::Float(0.0));
    let _ = ds.set(w, "w", Value::Float(WIDTH as f64));
    let _ = ds.set(w, "h", Value::Float(h as f64));
    let _ = ds.set(w, "native", Value::Bool(true));
    let _ = ds.set(w, "component", Value::str("ContextMenu"));
    true
}

/// The row under a widget-local y, if any.
pub fn row_at(y: f32, items: usize) -> Option<usize> {
    let r = ((y - TITLE) / ROW).floor();
    (r >= 0.0 && (r as usize) < items).then_some(r as usize)
}

/// Runs row `i` of the open menu widget `w` and closes the menu.
pub fn choose(ds: &DataServer, w: Guid, i: usize) {
    let get = |k: &str| ds.try_get(w, PropName::new(k));
    let (Some(ty), Some(obj)) = (get("menu_type"), get("object")) else { return };
    let enabled = get(&format!("enabled{i}")) == Some(Value::Bool(true));
    if enabled && let Some(menu) = ty.as_str().and_then(|t| ds.resolve(&["display", "menus", t])) {
        ds.call(menu, "choose", vec![Value::Int(i as i64), obj], None, |_| {});
    }
    if enabled {
        close(ds);
    }
}
