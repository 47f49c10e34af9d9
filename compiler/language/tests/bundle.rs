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
