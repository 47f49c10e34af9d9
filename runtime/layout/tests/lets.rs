//! `let`s are shared, not copied: long chains of `let`s, each built on the one before, and
//! doubling ones (`let a1 = a0 + a0`, `let a2 = a1 + a1`, …, which copied into their uses
//! would double per line) check clean, load into the runtime through the path `mocu run`
//! takes, and compute what the source says, with the JIT and with the interpreter.
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
