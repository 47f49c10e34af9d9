//! `let`s are shared, not copied: long chains of `let`s, each built on the one before, and
//! doubling ones (`let a1 = a0 + a0`, `let a2 = a1 + a1`, …, which copied into their uses
//! would double per line) check clean, load into the runtime through the path `mocu run`
//! takes, and compute what the source says, with the JIT and with the interpreter. A `let`
//! that several widgets read is compiled and evaluated once (a node of the graph), so what
//! is compiled stays as large as the source (counted in IR nodes, `LayoutStats::ir_nodes`).
mod common;
use common::program;
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;
use std::time::Duration;

/// A layout showing `a{last}` in a label, after `lets` (which start from the speed).
fn layout(lets: &str, last: &str) -> String {
    format!(
        "use \"stdlib/gauges.mocu\"\nlet a0 = root.vehicles.usv1.nav.speed\n{lets}\
         window hud {{ layer 1  rect 0 0 100 100 }}\n\
         in hud {{ out: Label {{ at 0 0  text \"{{{last}}}\" }} }}\n"
    )
}

/// `n` `let`s after `a0`, each adding one to the one before: the last is the speed + n.
fn chain(n: usize) -> String {
    let lets: String = (1..=n).map(|i| format!("let a{i} = a{} + 1\n", i - 1)).collect();
    layout(&lets, &format!("a{n}"))
}

/// `n` `let`s after `a0`, each the one before twice: the last is the speed × 2ⁿ.
fn doubling(n: usize) -> String {
    let lets: String = (1..=n).map(|i| format!("let a{i} = a{0} + a{0}\n", i - 1)).collect();
    layout(&lets, &format!("a{n}"))
}

/// Checks `text`, loads it with the JIT and with the interpreter, sets the speed and
/// returns the label's text under each.
fn shown(text: &str, speed: f64) -> Vec<Value> {
    // The checker and the runtime run on a thread with `mocu run`'s main-thread stack.
    let text = text.to_string();
    std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            let program = program(&text);
            [true, false]
                .into_iter()
                .map(|jit| {
                    let ds = DataServer::default();
                    let config =
                        LayoutConfig { tick: Duration::from_millis(1), jit, ..Default::default() };
                    let layout = Layout::load(&ds, &program, config, Arc::new(NullSink))
                        .unwrap_or_else(|e| {
                            panic!("`mocu check` passed it, `mocu run` refuses: {e}")
                        });
                    let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder"));
                    let v = ds.create_object(vs.unwrap(), ObjectInfo::new("usv1", "usv")).unwrap();
                    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
                    ds.set(nav, "speed", Value::Float(speed)).unwrap();
                    layout.settle();
                    let label = ds.resolve(&["display", "hud", "out"]).expect("label published");
                    ds.get(label, "text").unwrap()
                })
                .collect()
        })
        .unwrap()
        .join()
        .unwrap()
}

#[test]
fn chains_of_5000_and_50000_lets_check_load_and_compute_their_value() {
    for n in [5_000, 50_000] {
        let want = Value::str(&format!("{}", 2.5 + n as f64));
        assert_eq!(shown(&chain(n), 2.5), vec![want.clone(), want], "a chain of {n}");
    }
}

#[test]
fn twenty_and_sixty_doubling_lets_check_load_and_compute_their_value() {
    for n in [20, 60] {
        let want = Value::str(&format!("{}", 3.0 * 2f64.powi(n as i32)));
        assert_eq!(shown(&doubling(n), 3.0), vec![want.clone(), want], "{n} doubling lets");
    }
}

#[test]
fn forty_doubling_untyped_lets_are_lowered_once_each() {
    // Without a schema `??` of paths is untyped: its uses decide what it is read as, so it
    // is lowered where first read, then shared (not 2^40 copies).
    let lets: String = (1..=40).map(|i| format!("let a{i} = a{0} ?? a{0}\n", i - 1)).collect();
    let want = Value::str("7.5");
    assert_eq!(shown(&layout(&lets, "a40"), 7.5), vec![want.clone(), want]);
}

/// A layout of `widgets` labels, label `i` showing `a{shows(i)}`, after a chain of `n`
/// `let`s from the speed (`a{i} = a{i-1} + 1`).
fn many_readers(n: usize, widgets: usize, shows: impl Fn(usize) -> usize) -> String {
    let lets: String = (1..=n).map(|i| format!("let a{i} = a{} + 1\n", i - 1)).collect();
    let labels: String = (0..widgets)
        .map(|w| format!("  w{w}: Label {{ at 0 0  text \"{{a{}}}\" }}\n", shows(w)))
        .collect();
    format!(
        "use \"stdlib/gauges.mocu\"\nlet a0 = root.vehicles.usv1.nav.speed\n{lets}\
         window hud {{ layer 1  rect 0 0 100 100 }}\nin hud {{\n{labels}}}\n"
    )
}

/// Loads `text` (JIT or interpreter), sets the speed twice, and returns the layout's
/// statistics and what the labels named in `labels` show.
fn load_and_read(text: &str, jit: bool, labels: &[String]) -> (LayoutStats, Vec<Value>) {
    let program = program(text);
    let ds = DataServer::default();
    let config = LayoutConfig { tick: Duration::from_millis(1), jit, ..Default::default() };
    let layout = Layout::load(&ds, &program, config, Arc::new(NullSink)).expect("loads");
    let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    for speed in [1.0, 2.5] {
        ds.set(nav, "speed", Value::Float(speed)).unwrap();
        layout.settle();
    }
    let shown = labels
        .iter()
        .map(|l| {
            let g = ds.resolve(&["display", "hud", l]).expect("label published");
            ds.get(g, "text").unwrap()
        })
        .collect();
    (layout.stats(), shown)
}

/// IR nodes compiled for `widgets` labels showing the end of a chain of `n` `let`s.
fn ir_nodes(n: usize, widgets: usize) -> usize {
    let (stats, _) = load_and_read(&many_readers(n, widgets, |_| n), false, &[]);
    stats.ir_nodes
}

#[test]
fn a_let_that_many_widgets_show_is_compiled_once_not_once_per_widget() {
    // One label more costs its own function, not another copy of the 2,000-long chain.
    let n = 2_000;
    let (one, ten, hundred) = (ir_nodes(n, 1), ir_nodes(n, 10), ir_nodes(n, 100));
    assert!(one >= n, "the chain itself is compiled: {one} IR nodes");
    let per_label = (hundred - ten) / 90;
    assert!(per_label < 100, "each label adds {per_label} IR nodes ({one}, {ten}, {hundred})");
    assert!(hundred < one + 100 * 100, "100 labels: {hundred} IR nodes, 1 label: {one}");
}

#[test]
fn labels_showing_every_let_of_a_chain_compile_in_linear_size() {
    // Label i shows a{i}: every `let` is read by a label and by the next `let`, so each is
    // a shared node of the graph; copied into each label this would be n²/2.
    let n = 1_000;
    let text = many_readers(n, n, |w| w + 1);
    let labels: Vec<String> = (0..n).map(|w| format!("w{w}")).collect();
    for jit in [false, true] {
        let (stats, shown) = load_and_read(&text, jit, &labels);
        assert!(stats.ir_nodes < 40 * n, "{} IR nodes for {n} lets and labels", stats.ir_nodes);
        assert_eq!(stats.shared_lets, n - 1, "a1 … a{} are shared", n - 1);
        let want: Vec<Value> =
            (0..n).map(|w| Value::str(&format!("{}", 2.5 + (w + 1) as f64))).collect();
        assert_eq!(shown, want, "jit: {jit}");
    }
}

#[test]
fn a_shared_let_is_evaluated_once_per_change_and_its_readers_once_each() {
    // Two labels read a1 (shared); a third reads a0 and a1 (`a1 - a0` is always 1: no reader
    // may see a new a0 with an old a1).
    let text = "use \"stdlib/gauges.mocu\"\nlet a0 = root.vehicles.usv1.nav.speed\n\
                let a1 = a0 + 1\nwindow hud { layer 1  rect 0 0 100 100 }\nin hud {\n\
                x: Label { at 0 0  text \"{a1}\" }\n  y: Label { at 0 0  text \"{a1 * 2}\" }\n\
                d: Label { at 0 0  text \"{a1 - a0}\" }\n}\n";
    let program = program(text);
    for jit in [false, true] {
        let ds = DataServer::default();
        let config = LayoutConfig { tick: Duration::from_millis(1), jit, ..Default::default() };
        let layout = Layout::load(&ds, &program, config, Arc::new(NullSink)).unwrap();
        let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
        let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
        let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
        let d = ds.resolve(&["display", "hud", "d"]).unwrap();
        let before = layout.stats();
        assert_eq!(before.shared_lets, 1, "a1 is shared (a0 is a path: each reads it)");
        ds.set(nav, "speed", Value::Float(4.0)).unwrap();
        layout.settle();
        let after = layout.stats();
        assert_eq!(ds.get(d, "text").unwrap(), Value::str("1"));
        // a1's cell, x, y and d: once each.
        assert_eq!(after.evaluations - before.evaluations, 4, "jit: {jit}");
        let x = ds.resolve(&["display", "hud", "x"]).unwrap();
        assert_eq!(ds.get(x, "text").unwrap(), Value::str("5"));
        // Absent stays absent through the node.
        ds.delete_property(nav, "speed").unwrap();
        layout.settle();
        assert_eq!(ds.get(x, "text").unwrap(), Value::str("—"), "jit: {jit}");
    }
}

#[test]
fn a_widget_reading_a_vehicle_through_a_shared_let_goes_stale_with_the_vehicle() {
    // x and y read the speed only through a1, a shared `let` (a node of its own): they are
    // stale when usv1 says its data is old, as if they read the speed themselves.
    let text = "use \"stdlib/gauges.mocu\"\nlet a1 = root.vehicles.usv1.nav.speed + 1\n\
                window hud { layer 1  rect 0 0 100 100 }\nin hud {\n\
                x: Label { at 0 0  text \"{a1}\" }\n  y: Label { at 0 0  text \"{a1 * 2}\" }\n}\n";
    let program = program(text);
    let ds = DataServer::default();
    let layout = Layout::load(&ds, &program, common::config(), Arc::new(NullSink)).unwrap();
    assert_eq!(layout.stats().shared_lets, 1);
    let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(nav, "speed", Value::Float(1.0)).unwrap();
    layout.settle();
    let x = ds.resolve(&["display", "hud", "x"]).unwrap();
    assert_ne!(ds.try_get(x, PropName::new("stale")), Some(Value::Bool(true)));
    ds.set(v, "link_lost", Value::Bool(true)).unwrap();
    layout.settle();
    for w in ["x", "y"] {
        let g = ds.resolve(&["display", "hud", w]).unwrap();
        assert_eq!(ds.try_get(g, PropName::new("stale")), Some(Value::Bool(true)), "{w}");
    }
}
