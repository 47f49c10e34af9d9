//! Templates that flow (`for each v in … flow down rect X Y W H gap N { … }`): each
//! instance's windows, as one block (the box around them), are placed by the runtime one
//! after another in the flow's region — down a column and on to the next column on its right,
//! or along a row and on to the next row below — in the order of the instances' `index`.
//! An instance whose windows are all hidden by their own `visible` takes no room. Instances
//! that do not fit are hidden, and a built-in window `<first window>+more` at the end of the
//! flow says "+N more" (its `more` property is N; the native `FlowMore` widget in it draws it).
//! The window cells compute each instance window's box as usual; their `x`, `y`, `w`, `h`
//! and `visible` come here ([`super::Target::FlowBox`]) and the placement writes them after
//! each evaluation that changed a box, the region or the instances.

use super::compile::{Builder, Frame, place};
use super::{LoadError, Shared, State, Target};
use crate::lower::Scope;
use mocu_language::program::Flow;
use mocu_value::{Guid, PropName, Value};
use std::sync::Arc;

/// The native component of the "+N more" label (drawn by the widget renderer).
pub const MORE_COMPONENT: &str = "FlowMore";
/// The "+N more" label's size in design px (never below [`MORE_MIN`] screen px).
const MORE_SIZE: (f64, f64) = (112.0, 24.0);
const MORE_MIN: (f64, f64) = (72.0, 18.0);
/// A flowed window's outputs (of `WINDOW_OUTPUTS`) kept for the placement, in this order.
const BOX: [&str; 5] = ["x", "y", "w", "h", "visible"];

/// A template's flow at run time.
pub(crate) struct FlowRt {
    pub(crate) down: bool,
    /// Between two instances, in screen px.
    gap: f64,
    /// The design's scale (the label's size).
    scale: f64,
    /// Computes the region: x, y, w, h in screen px.
    region_f: super::FnRef,
    region_cell: Option<usize>,
    region: [Option<f64>; 4],
    pub(crate) dirty: bool,
    /// The "+N more" window's name and, once published, its window and widget.
    more_name: String,
    more: Option<(Guid, Guid)>,
    /// What was last written on the label window: shown, x, y, w, h, N.
    more_written: Option<[f64; 6]>,
}

/// One window of a flowed instance: its box as its cell computed it, and as last written.
#[derive(Clone)]
pub(crate) struct FlowBox {
    pub(crate) window: Guid,
    computed: [Option<Value>; 5],
    written: [Option<Value>; 5],
}

impl FlowBox {
    pub(crate) fn new(window: Guid) -> FlowBox {
        FlowBox { window, computed: Default::default(), written: Default::default() }
    }
}

/// Compiles a flow's region (placed like a window on the screen, by the design's scale).
pub(crate) fn compile_flow(
    b: &mut Builder,
    f: &Flow,
    frame: Frame,
    first_window: &str,
) -> Result<FlowRt, LoadError> {
    let screen = frame.screen;
    let mut lw = b.lowerer(Scope::Plain, screen);
    let mut parent = |_: &mut crate::lower::Lowerer, horizontal: bool| {
        Ok(mocu_jit::Expr::Num(if horizontal { screen.0 } else { screen.1 }))
    };
    let mut outs = place(&mut lw, &f.rect, f.anchor, frame.scale, &mut parent)?;
    outs.resize(4, mocu_jit::Expr::Num(0.0));
    let region_f = b.add(lw, outs);
    Ok(FlowRt {
        down: f.down,
        gap: (f.gap * frame.scale).max(0.0),
        scale: frame.scale,
        region_f,
        region_cell: None,
        region: [None; 4],
        dirty: true,
        more_name: format!("{first_window}+more"),
        more: None,
        more_written: None,
    })
}

/// The targets of a flowed window's cell (`WINDOW_OUTPUTS` order): `layer` and `opacity`
/// on the window, its box to the flow.
pub(crate) fn window_targets(g: Guid, instance: usize, window: usize) -> Vec<Target> {
    super::compile::WINDOW_OUTPUTS
        .iter()
        .map(|n| match BOX.iter().position(|b| b == n) {
            Some(field) => Target::FlowBox { instance, window, field },
            None => Target::Prop(g, PropName::new(n)),
        })
        .collect()
}

impl Shared {
    /// Starts template `t`'s flow: its region's cell and the "+N more" window (hidden).
    pub(crate) fn start_flow(self: &Arc<Self>, st: &mut State, t: usize) {
        let Some(f) = st.templates[t].flow.as_ref() else { return };
        let (func, name) = (f.region_f.clone(), f.more_name.clone());
        let targets = (0..4).map(|field| Target::FlowRegion { template: t, field }).collect();
        let cell = self.add_cell(st, &func, targets, None);
        let more = self.publish_more(st.display, &name);
        if let Some((w, _)) = more {
            st.owned.push(w);
        }
        if let Some(f) = st.templates[t].flow.as_mut() {
            f.region_cell = Some(cell);
            f.more = more;
            f.dirty = true;
        }
    }

    /// Ends template `t`'s flow (its instances are removed by the caller).
    pub(crate) fn stop_flow(self: &Arc<Self>, st: &mut State, t: usize) {
        let Some(f) = st.templates[t].flow.as_mut() else { return };
        let (cell, more) = (f.region_cell.take(), f.more.take());
        if let Some(c) = cell {
            self.remove_cell(st, c);
        }
        if let Some((w, _)) = more {
            st.owned.retain(|g| *g != w);
            let _ = self.ds.delete_object(w);
        }
    }

    fn publish_more(&self, display: Guid, name: &str) -> Option<(Guid, Guid)> {
        use mocu_dataserver::ObjectInfo;
        let ds = &self.ds;
        let w =
            ds.create_object(display, ObjectInfo::new(name, "window").subtype("widgets")).ok()?;
        for (k, v) in [
            ("order", Value::Int(2000)),
            ("revision", Value::Int(0)),
            ("clip", Value::Bool(true)),
            ("visible", Value::Bool(false)),
            ("more", Value::Int(0)),
        ] {
            let _ = ds.set(w, k, v);
        }
        let g = ds.create_object(w, ObjectInfo::new("more", "widget").subtype(MORE_COMPONENT));
        let Ok(g) = g else {
            let _ = ds.delete_object(w);
            return None;
        };
        for (k, v) in [
            ("component", Value::str(MORE_COMPONENT)),
            ("native", Value::Bool(true)),
            ("order", Value::Int(0)),
            ("x", Value::Float(0.0)),
            ("y", Value::Float(0.0)),
            ("count", Value::Int(0)),
        ] {
            let _ = ds.set(g, k, v);
        }
        Some((w, g))
    }

    /// Places every flow marked dirty since the last time.
    pub(crate) fn place_flows(self: &Arc<Self>, st: &mut State) {
        for t in 0..st.templates.len() {
            if st.templates[t].alive && st.templates[t].flow.as_ref().is_some_and(|f| f.dirty) {
                self.place_flow(st, t);
            }
        }
    }

    fn place_flow(self: &Arc<Self>, st: &mut State, t: usize) {
        let Some(f) = st.templates[t].flow.as_mut() else { return };
        f.dirty = false;
        let (down, gap, scale, region) = (f.down, f.gap, f.scale, f.region);
        let region = match region {
            [Some(x), Some(y), Some(w), Some(h)] => [x, y, w.max(0.0), h.max(0.0)],
            _ => [0.0; 4], // no region (yet): nothing fits
        };
        let mut mine: Vec<(usize, usize)> = (0..st.instances.len())
            .filter_map(|i| {
                st.instances[i].as_ref().filter(|x| x.template == t).map(|x| (x.index, i))
            })
            .collect();
        mine.sort_unstable();
        // Each instance's block: the box around its shown windows (none: it takes no room).
        let blocks: Vec<Option<[f64; 4]>> = mine
            .iter()
            .map(|&(_, i)| st.instances[i].as_ref().and_then(|x| block(&x.boxes)))
            .collect();
        let label = (
            (MORE_SIZE.0 * scale).max(MORE_MIN.0).min(region[2]),
            (MORE_SIZE.1 * scale).max(MORE_MIN.1),
        );
        let plan = plan(&blocks, region, gap, down, label);
        for (n, &(_, i)) in mine.iter().enumerate() {
            let (dx, dy, shown) = match (plan.at[n], blocks[n]) {
                (Some((x, y)), Some(b)) => (x - b[0], y - b[1], true),
                _ => (0.0, 0.0, false),
            };
            let Some(inst) = st.instances[i].as_mut() else { continue };
            for b in &mut inst.boxes {
                let num = |k: usize| b.computed[k].as_ref().and_then(Value::as_f64);
                let own = b.computed[4].as_ref().and_then(Value::as_bool) != Some(false);
                let out = [
                    num(0).map(|x| Value::Float(x + dx)),
                    num(1).map(|y| Value::Float(y + dy)),
                    b.computed[2].clone(),
                    b.computed[3].clone(),
                    Some(Value::Bool(own && shown)),
                ];
                for (k, v) in out.into_iter().enumerate() {
                    if b.written[k] == v {
                        continue;
                    }
                    let _ = match &v {
                        Some(v) => self.ds.set(b.window, BOX[k], v.clone()),
                        None => self.ds.delete_property(b.window, BOX[k]),
                    };
                    b.written[k] = v;
                }
            }
        }
        let layer = mine
            .iter()
            .filter_map(|&(_, i)| st.instances[i].as_ref()?.boxes.first().map(|b| b.window))
            .find_map(|w| self.ds.try_get(w, "layer".into()).and_then(|v| v.as_f64()));
        self.show_more(st, t, &plan, label, layer.unwrap_or(0.0), scale);
    }

    fn show_more(
        &self,
        st: &mut State,
        t: usize,
        plan: &Plan,
        label: (f64, f64),
        layer: f64,
        s: f64,
    ) {
        let Some(f) = st.templates[t].flow.as_mut() else { return };
        let Some((w, g)) = f.more else { return };
        let (x, y) = plan.more_at.unwrap_or((0.0, 0.0));
        let shown = plan.more > 0 && plan.more_at.is_some();
        let now = [f64::from(u8::from(shown)), x, y, label.0, label.1, plan.more as f64];
        if f.more_written == Some(now) {
            return;
        }
        f.more_written = Some(now);
        let ds = &self.ds;
        let _ = ds.set(w, "layer", Value::Float(layer));
        for (k, v) in [("x", x), ("y", y), ("w", label.0), ("h", label.1)] {
            let _ = ds.set(w, k, Value::Float(v));
        }
        let _ = ds.set(g, "w", Value::Float(label.0));
        let _ = ds.set(g, "h", Value::Float(label.1));
        let _ = ds.set(g, "scale", Value::Float(s.max(1.0)));
        let _ = ds.set(g, "count", Value::Int(plan.more as i64));
        let _ = ds.set(w, "more", Value::Int(plan.more as i64));
        let _ = ds.set(w, "visible", Value::Bool(shown));
    }
}

/// A flowed window's output, from its cell.
pub(crate) fn on_box(
    st: &mut State,
    instance: usize,
    window: usize,
    field: usize,
    v: Option<Value>,
) {
    let Some(inst) = st.instances.get_mut(instance).and_then(Option::as_mut) else { return };
    let t = inst.template;
    if let Some(b) = inst.boxes.get_mut(window) {
        b.computed[field] = v;
    }
    mark(st, t);
}

/// A flow's region, from its cell.
pub(crate) fn on_region(st: &mut State, t: usize, field: usize, v: Option<Value>) {
    if let Some(f) = st.templates.get_mut(t).and_then(|t| t.flow.as_mut()) {
        f.region[field] = v.and_then(|v| v.as_f64()).filter(|x| x.is_finite());
        f.dirty = true;
    }
}

/// Template `t`'s flow is placed again after this evaluation.
pub(crate) fn mark(st: &mut State, t: usize) {
    if let Some(f) = st.templates.get_mut(t).and_then(|t| t.flow.as_mut()) {
        f.dirty = true;
    }
}

/// The box around an instance's shown windows: x, y, w, h (None when none is shown).
fn block(boxes: &[FlowBox]) -> Option<[f64; 4]> {
    let mut out: Option<[f64; 4]> = None;
    for b in boxes {
        if b.computed[4].as_ref().and_then(Value::as_bool) == Some(false) {
            continue;
        }
        let n = |k: usize| b.computed[k].as_ref().and_then(Value::as_f64).unwrap_or(0.0);
        let (x0, y0, x1, y1) = (n(0), n(1), n(0) + n(2).max(0.0), n(1) + n(3).max(0.0));
        out = Some(match out {
            None => [x0, y0, x1, y1],
            Some(o) => [o[0].min(x0), o[1].min(y0), o[2].max(x1), o[3].max(y1)],
        });
    }
    out.map(|o| [o[0], o[1], o[2] - o[0], o[3] - o[1]])
}

/// Where the blocks go: each shown block's top-left, and the "+N more" label's.
#[derive(Debug, PartialEq)]
pub(crate) struct Plan {
    pub(crate) at: Vec<Option<(f64, f64)>>,
    pub(crate) more: usize,
    pub(crate) more_at: Option<(f64, f64)>,
}

/// The flow's cursor: where the next block goes, down a column (or along a row).
#[derive(Clone, Copy)]
struct Cursor {
    region: [f64; 4],
    gap: f64,
    down: bool,
    /// Along the flow, and across it (the column's or row's start).
    along: f64,
    across: f64,
    /// The widest block of the column (the tallest of the row) so far; none yet.
    thick: Option<f64>,
}

/// Room for rounding: a block exactly as large as the region fits.
const EPS: f64 = 0.01;

impl Cursor {
    fn new(region: [f64; 4], gap: f64, down: bool) -> Cursor {
        let (along, across) = if down { (region[1], region[0]) } else { (region[0], region[1]) };
        Cursor { region, gap, down, along, across, thick: None }
    }

    /// Puts a block of size `w` × `h`: its top-left, or None when it does not fit.
    fn put(&mut self, w: f64, h: f64) -> Option<(f64, f64)> {
        let r = self.region;
        // (start, length) of the region along and across the flow, and the block's.
        let (a0, alen, c0, clen) =
            if self.down { (r[1], r[3], r[0], r[2]) } else { (r[0], r[2], r[1], r[3]) };
        let (bl, bt) = if self.down { (h, w) } else { (w, h) };
        let mut next = *self;
        if let Some(t) = next.thick
            && next.along + bl > a0 + alen + EPS
        {
            next.across += t + self.gap;
            next.along = a0;
            next.thick = None;
        }
        if next.along + bl > a0 + alen + EPS || next.across + bt > c0 + clen + EPS {
            return None;
        }
        let at = if self.down { (next.across, next.along) } else { (next.along, next.across) };
        next.along += bl + self.gap;
        next.thick = Some(next.thick.map_or(bt, |t| t.max(bt)));
        *self = next;
        Some(at)
    }
}

/// Places the blocks in order (None: takes no room). When some do not fit, as many as leave
/// room after them for the label are shown and the label follows them.
pub(crate) fn plan(
    blocks: &[Option<[f64; 4]>],
    region: [f64; 4],
    gap: f64,
    down: bool,
    label: (f64, f64),
) -> Plan {
    let mut cur = Cursor::new(region, gap, down);
    let mut at = vec![None; blocks.len()];
    // The last prefix after which the label fits: (blocks placed, where the label goes).
    let mut last = (0, cur.clone().put(label.0, label.1));
    let mut all = true;
    for (n, b) in blocks.iter().enumerate() {
        let Some(b) = b else {
            if last.0 == n {
                last.0 = n + 1;
            }
            continue;
        };
        match cur.put(b[2], b[3]) {
            Some(p) => {
                at[n] = Some(p);
                if let Some(l) = cur.clone().put(label.0, label.1) {
                    last = (n + 1, Some(l));
                }
            }
            None => {
                all = false;
                break;
            }
        }
    }
    if all {
        return Plan { at, more: 0, more_at: None };
    }
    let fitted = at.iter().rposition(Option::is_some).map_or(0, |p| p + 1);
    let (keep, more_at) = match last {
        (keep, Some(l)) if fitted == 0 || at[..keep].iter().any(Option::is_some) => (keep, Some(l)),
        // No room for the label after one block at least: the blocks that fit, without it.
        _ => (fitted, None),
    };
    for a in at.iter_mut().skip(keep) {
        *a = None;
    }
    let more = blocks.iter().enumerate().filter(|(n, b)| b.is_some() && at[*n].is_none()).count();
    Plan { at, more, more_at: more_at.filter(|_| more > 0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strips(n: usize) -> Vec<Option<[f64; 4]>> {
        vec![Some([0.0, 0.0, 400.0, 92.0]); n]
    }

    #[test]
    fn a_column_fills_then_the_rest_is_counted() {
        // 446 px high: four strips of 92 with gaps of 8 (392), then the label (24).
        let p = plan(&strips(8), [20.0, 20.0, 400.0, 446.0], 8.0, true, (112.0, 24.0));
        let ys: Vec<f64> = p.at.iter().flatten().map(|a| a.1).collect();
        assert_eq!(ys, [20.0, 120.0, 220.0, 320.0]);
        assert_eq!((p.more, p.more_at), (4, Some((20.0, 420.0))));
        let all = plan(&strips(4), [20.0, 20.0, 400.0, 446.0], 8.0, true, (112.0, 24.0));
        assert_eq!((all.at.iter().flatten().count(), all.more, all.more_at), (4, 0, None));
    }

    #[test]
    fn a_column_wraps_to_the_next_and_a_row_to_the_next_below() {
        let p = plan(&strips(3), [0.0, 0.0, 900.0, 200.0], 10.0, true, (100.0, 20.0));
        assert_eq!(p.at, [Some((0.0, 0.0)), Some((0.0, 102.0)), Some((410.0, 0.0))]);
        let tiles = vec![Some([0.0, 0.0, 100.0, 50.0]); 3];
        let p = plan(&tiles, [0.0, 0.0, 250.0, 200.0], 10.0, false, (100.0, 20.0));
        assert_eq!(p.at, [Some((0.0, 0.0)), Some((110.0, 0.0)), Some((0.0, 60.0))]);
    }

    #[test]
    fn a_hidden_instance_takes_no_room_and_the_label_needs_room_of_its_own() {
        let mut b = strips(3);
        b[1] = None;
        let p = plan(&b, [0.0, 0.0, 400.0, 200.0], 8.0, true, (112.0, 24.0));
        assert_eq!(p.at, [Some((0.0, 0.0)), None, Some((0.0, 100.0))]);
        assert_eq!(p.more, 0);
        // Room for one strip and no label: the strip is shown, the label is not.
        let p = plan(&strips(2), [0.0, 0.0, 400.0, 100.0], 8.0, true, (112.0, 24.0));
        assert_eq!((p.at[0], p.at[1], p.more, p.more_at), (Some((0.0, 0.0)), None, 1, None));
    }
}
