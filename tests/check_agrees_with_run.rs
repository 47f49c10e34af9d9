//! `mocu check` passes only what `mocu run` accepts: every layout of the test corpus (the
//! shipped layouts through their profile, the stdlib, the syntax tests, and generated
//! stress layouts) is checked the way `mocu run` checks it (`load_target`), and each one
//! that checks clean is loaded into the runtime against a DataServer with the simulator
//! publishing its vehicles. A clean check that the runtime refuses is a failure.

use mocu_dataserver::DataServer;
use mocu_host::ModuleContext;
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_sim::{Sim, SimConfig};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn mocu_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).unwrap().filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            mocu_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "mocu") {
            out.push(p);
        }
    }
}

/// Stress layouts written to a scratch folder: long `let` chains, deep nesting.
fn generated(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut write = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        out.push(p);
    };
    for n in [10, 40, 80, 300] {
        let mut t = String::from("let a0 = root.vehicles.usv1.nav.speed\n");
        for i in 1..n {
            t.push_str(&format!("let a{i} = a{} + 1\n", i - 1));
        }
        t.push_str(&format!("window w {{ layer 1  visible a{} > 0 }}\n", n - 1));
        write(&format!("let_chain_{n}.mocu"), t);
    }
    // Untyped `let`s (no schema: `??` of unknown paths) are put in place at their uses, so
    // this chain is as deep as it is long.
    let mut t = String::from("let a0 = root.vehicles.usv1.nav.speed\n");
    for i in 1..300 {
        t.push_str(&format!("let a{i} = a{} ?? root.vehicles.usv1.fuel\n", i - 1));
    }
    t.push_str("window w { layer 1  visible a299 > 0 }\n");
    write("untyped_let_chain_300.mocu", t);
    for n in [50, 100, 250] {
        let e = format!("{}root.vehicles.usv1.fuel{}", "(".repeat(n), ")".repeat(n));
        write(&format!("parens_{n}.mocu"), format!("window w {{ layer 1  visible {e} > 0 }}\n"));
        let sum = vec!["root.vehicles.usv1.fuel"; n].join(" + ");
        write(&format!("sum_{n}.mocu"), format!("window w {{ layer 1  visible {sum} > 0 }}\n"));
    }
    out
}

#[test]
fn every_layout_that_checks_clean_loads_into_the_runtime() {
    // The stack of `mocu check` and `mocu run`'s main thread (8 MiB), not a test thread's.
    std::thread::Builder::new().stack_size(8 << 20).spawn(corpus_agrees).unwrap().join().unwrap();
}

fn corpus_agrees() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scratch = tempfile::tempdir().unwrap();
    let mut targets = vec![root.join("layouts/project.toml")];
    mocu_files(&root.join("stdlib"), &mut targets);
    mocu_files(&root.join("compiler/language/tests/syntax"), &mut targets);
    targets.extend(generated(scratch.path()));

    let ds = DataServer::default();
    let sim = Sim::new(ModuleContext::detached("sim", ds.clone()), SimConfig::default()).unwrap();
    sim.step(5.0);
    let (mut clean, mut refused_by_check) = (0, 0);
    let mut disagreements = Vec::new();
    for t in &targets {
        let bundle = match mocu_language::load_target(t) {
            Ok((bundle, _warnings)) => bundle,
            Err(_) => {
                refused_by_check += 1;
                continue;
            }
        };
        for layout in &bundle.layouts {
            clean += 1;
            let config = LayoutConfig { screen: (1920.0, 1080.0), ..LayoutConfig::default() };
            match Layout::load(&ds, &layout.program, config, Arc::new(NullSink)) {
                Ok(l) => {
                    l.settle();
                    drop(l);
                }
                Err(e) => disagreements.push(format!("{} ({}): {e}", t.display(), layout.path)),
            }
        }
    }
    assert!(
        disagreements.is_empty(),
        "`mocu check` passed these, `mocu run` refuses them:\n{}",
        disagreements.join("\n")
    );
    assert!(clean >= 20, "the corpus shrank: {clean} clean layouts");
    assert!(refused_by_check >= 30, "the corpus has its broken files: {refused_by_check}");
}

#[test]
fn a_chain_of_300_untyped_lets_is_refused_by_check_at_its_use_not_by_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = generated(dir.path())
        .into_iter()
        .find(|p| p.ends_with("untyped_let_chain_300.mocu"))
        .unwrap();
    match mocu_language::load_target(&path) {
        Err(mocu_language::LoadError::Diagnostics { rendered, .. }) => {
            assert!(rendered.contains("E0106") && rendered.contains(":301:"), "{rendered}")
        }
        other => panic!("a 300-deep chain must not check clean: {:?}", other.map(|_| ())),
    }
}

/// What the simulator publishes under a vehicle, checked against the shipped schema: each
/// child, property (by value kind) and method (by parameter kinds) must be declared, or a
/// layout using it would fail `mocu check` although `mocu run` accepts it.
#[test]
fn the_shipped_schema_declares_everything_the_simulator_publishes() {
    use mocu_language::schema::Schema;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("layouts/schemas/vehicles.toml")).unwrap();
    let schema: Schema = toml::from_str(&text).unwrap();
    let ds = DataServer::default();
    let cfg = SimConfig { autostart: true, ..SimConfig::default() };
    let sim = Sim::new(ModuleContext::detached("sim", ds.clone()), cfg).unwrap();
    sim.step(5.0);
    ds.quiesce();
    let vehicles = ds.snapshot(ds.resolve(&["vehicles"]).unwrap()).unwrap();
    let mut missing = Vec::new();
    /// Looks every member up the way `mocu check` does (from `root`).
    fn walk(
        ds: &DataServer,
        schema: &Schema,
        s: &mocu_dataserver::Snapshot,
        path: &[String],
        missing: &mut Vec<String>,
    ) {
        use mocu_language::schema::Lookup;
        let at = |n: &str| {
            let mut p = path.to_vec();
            p.push(n.to_string());
            p
        };
        let text = |p: &[String]| format!("root.{}", p.join("."));
        for (name, value) in &s.properties {
            let p = at(name);
            match schema.lookup(None, true, &p) {
                Lookup::Property(d) if d.kind == value.kind() => {}
                Lookup::Property(d) => missing.push(format!(
                    "{}: schema {}, published {}",
                    text(&p),
                    d.kind,
                    value.kind()
                )),
                _ => missing.push(format!("{} ({})", text(&p), value.kind())),
            }
        }
        for m in ds.methods(s.guid).unwrap_or_default() {
            let got: Vec<_> = m.params.iter().filter_map(|p| p.kind).collect();
            let p = at(m.name.as_str());
            match schema.lookup(None, true, &p) {
                Lookup::Method(d) if d.params == got => {}
                _ => missing.push(format!("{}({got:?})", text(&p))),
            }
        }
        for c in &s.children {
            let p = at(&c.name);
            match schema.lookup(None, true, &p) {
                Lookup::Object(_) => walk(ds, schema, c, &p, missing),
                _ => missing.push(format!("object {} (kind {})", text(&p), c.kind)),
            }
        }
    }
    for v in &vehicles.children {
        walk(&ds, &schema, v, &["vehicles".to_string(), v.name.clone()], &mut missing);
    }
    missing.sort();
    missing.dedup();
    assert!(missing.is_empty(), "layouts/schemas/vehicles.toml lacks:\n{}", missing.join("\n"));
}
