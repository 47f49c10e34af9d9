//! The shipped layouts (`layouts/*.mocu`), for the tests that check every one of them.

use std::path::PathBuf;

/// Every `.mocu` file of `layouts/`, sorted.
pub fn layouts() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../layouts");
    let mut out: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "mocu"))
        .collect();
    out.sort();
    assert!(out.len() >= 4, "the shipped layouts");
    out
}
