//! Bundles round-trip, and a tampered or foreign bundle is refused with a clear message.

use mocu_language::{Diagnostics, MemoryLoader, SourceMap, bundle, check_path};

fn built() -> mocu_language::Bundle {
    let loader = MemoryLoader::new()
        .with("p/project.toml", "[profile]\nname = \"t\"\nlayouts = [\"a.mocu\"]\n[modules.sim]\nvehicles = [\"usv1\"]\n")
        .with("p/a.mocu", "window w { layer 1 }\nwatch low { when root.vehicles.usv1.fuel < 0.2 then alert warning \"low\" }\n");
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let text = loader.files["p/project.toml"].clone();
    let b = check_path("p/project.toml", text, &loader, &mut sources, &mut diags)
        .expect("a profile gives a bundle");
    assert!(diags.is_empty(), "{:?}", diags.into_vec());
    b
}

#[test]
fn a_bundle_reads_back_equal() {
    let b = built();
    let bytes = bundle::write(&b);
    assert!(bytes.starts_with(b"MOCU-BUNDLE v1 mocu "));
    assert_eq!(bundle::read(&bytes), Ok(b.clone()));
    let watch = &b.layouts[0].program.watches[0];
    assert_eq!(watch.when.paths.len(), 1, "the subscription set is the one path read");
    assert_eq!(watch.when.paths[0].to_string(), "root.vehicles.usv1.fuel");
    assert_eq!(b.profile.as_ref().map(|p| p.modules.contains_key("sim")), Some(true));
}

#[test]
fn a_tampered_bundle_is_refused() {
    let mut bytes = bundle::write(&built());
    let last = bytes.len() - 2;
    bytes[last] ^= 0x01;
    let e = bundle::read(&bytes).expect_err("tampered");
    assert!(e.to_string().contains("corrupt"), "{e}");
}

#[test]
fn a_bundle_from_another_version_is_refused() {
    let bytes = bundle::write(&built());
    let text = String::from_utf8(bytes).expect("utf-8");
    let other = text.replacen(&format!("mocu {}", bundle::VERSION), "mocu 0.0.1", 1);
    let e = bundle::read(other.as_bytes()).expect_err("other version");
    assert!(matches!(e, bundle::BundleError::Version { .. }));
    assert!(
        e.to_string().contains("built by mocu 0.0.1") && e.to_string().contains("rebuild"),
        "{e}"
    );
    let v2 = text.replacen("v1", "v2", 1);
    assert!(matches!(bundle::read(v2.as_bytes()), Err(bundle::BundleError::Version { .. })));
    assert_eq!(bundle::read(b"window w {}"), Err(bundle::BundleError::NotABundle));
}

/// A layout of shared `let`s: 60 doubling ones and a chain of 2,000, as a one-layout bundle.
fn built_with_lets() -> mocu_language::Bundle {
    let mut layout = String::from("let d0 = root.vehicles.usv1.fuel\nlet c0 = d0\n");
    for i in 1..=60 {
        layout.push_str(&format!("let d{i} = d{0} + d{0}\n", i - 1));
    }
    for i in 1..=2000 {
        layout.push_str(&format!("let c{i} = c{} + root.vehicles.usv{}.fuel\n", i - 1, i % 3));
    }
    layout.push_str("window w { layer 1  visible d60 + c2000 > 0 }\n");
    let loader = MemoryLoader::new().with("l.mocu", &layout);
    let (mut sources, mut diags) = (SourceMap::new(), Diagnostics::new());
    let b = check_path("l.mocu", layout.clone(), &loader, &mut sources, &mut diags)
        .expect("a layout gives a bundle");
    assert!(!diags.has_errors(), "{:?}", diags.into_vec());
    b
}

#[test]
fn shared_lets_are_stored_once_and_read_back_equal() {
    let b = built_with_lets();
    let program = &b.layouts[0].program;
    assert_eq!(program.lets.0.len(), 60 + 2000, "each let once (d0 and c0 are paths, copied)");
    let visible = &program.windows[0].visible;
    let paths: Vec<String> = visible.paths.iter().map(|p| p.to_string()).collect();
    assert_eq!(
        paths,
        ["root.vehicles.usv1.fuel", "root.vehicles.usv2.fuel", "root.vehicles.usv0.fuel"],
        "the subscription set reaches through the lets, each path once, in order of appearance"
    );
    let bytes = bundle::write(&b);
    assert!(bytes.len() < 2_000_000, "stored as written, not expanded: {} bytes", bytes.len());
    assert_eq!(bundle::read(&bytes), Ok(b.clone()));
}

#[test]
fn a_bundle_whose_let_is_used_before_it_is_defined_is_refused() {
    let bytes = bundle::write(&built_with_lets());
    let body_at = bytes.iter().position(|b| *b == b'\n').unwrap() + 1;
    let mut body: serde_json::Value = serde_json::from_slice(&bytes[body_at..]).unwrap();
    body["layouts"][0]["program"]["lets"].as_array_mut().unwrap().truncate(10);
    let body = serde_json::to_vec(&body).unwrap();
    let header = format!(
        "MOCU-BUNDLE v1 mocu {} crc32={:08x} len={}\n",
        bundle::VERSION,
        bundle::crc32(&body),
        body.len()
    );
    let e = bundle::read(&[header.as_bytes(), &body].concat()).expect_err("dangling let");
    assert!(e.to_string().contains("is not defined before its use"), "{e}");
}
