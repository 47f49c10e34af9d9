//! `mocu lsp` end to end with a real LSP client: tests/peers/lsp/test_mocu_lsp.py, run by
//! pytest with pytest-lsp (CI pins it in .ci/run), drives the built `mocu lsp` over stdio as an
//! editor does; tests/peers/lsp/test_live_values.py does it with a running `mocu serve` whose
//! vehicles completion and hover show live. Every Python test must pass: none may be skipped,
//! and a missing pytest-lsp fails here with the install line instead of passing silently.

use std::process::Command;

const TESTS: [&str; 2] =
    ["tests/peers/lsp/test_mocu_lsp.py", "tests/peers/lsp/test_live_values.py"];

#[test]
fn mocu_lsp_passes_the_language_client_tests_open_edit_diagnostics_completion_hover_definition_rename_live_values()
 {
    let root = env!("CARGO_MANIFEST_DIR");
    let o = Command::new("python3")
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "-o",
            "asyncio_mode=auto",
            "-o",
            "asyncio_default_fixture_loop_scope=function",
        ])
        .args(TESTS)
        .current_dir(root)
        .env("MOCU_BIN", env!("CARGO_BIN_EXE_mocu"))
        .output()
        .expect("python3 runs (CI installs it)");
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !out.contains("No module named") && !err.contains("No module named"),
        "this test needs pytest-lsp: `python3 -m pip install pytest-lsp==1.0.1`\n{out}{err}"
    );
    let summary = out.lines().last().unwrap_or("");
    assert!(o.status.success(), "the client tests failed:\n{out}{err}");
    assert!(summary.contains(" passed"), "no client test ran:\n{out}{err}");
    for word in ["skipped", "failed", "error", "xfail", "deselected"] {
        assert!(!summary.contains(word), "{word} in the summary `{summary}`:\n{out}");
    }
}
