//! What the layout tests share: a layout checked from text, and a fast-ticking config.
#![allow(dead_code)] // each test binary uses its own part

use mocu_layout::LayoutConfig;
use std::time::Duration;

/// The checked program of a one-file layout (stdlib `use`s resolve as in a project).
pub fn program(text: &str) -> mocu_language::Program {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("test.mocu");
    std::fs::write(&path, text).unwrap();
    match mocu_language::load_target(&path) {
        Ok((bundle, _)) => bundle.layouts.into_iter().next().unwrap().program,
        Err(e) => panic!("layout does not check:\n{e}"),
    }
}

/// A layout ticking every millisecond.
pub fn config() -> LayoutConfig {
    LayoutConfig { tick: Duration::from_millis(1), ..LayoutConfig::default() }
}
