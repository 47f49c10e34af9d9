//! ARCHITECTURE.md's invariants as tests (in the spirit of rust-analyzer's `tidy`): the
//! dependency rules read from `cargo metadata`, the source rules from a scan of every `.rs`
//! file of the workspace. Each failure names the crate or the file and line that breaks the
//! rule, and the rule. Allowlists below are debts, each with a FIXME: shorten them, never
//! lengthen them without saying why in ARCHITECTURE.md.

#![forbid(unsafe_code)]

mod architecture_support;

use architecture_support::{Graph, code_only, rust_files, workspace_root};
use std::collections::BTreeSet;

/// Which crates of ours each crate may depend on (normal and build dependencies; dev
/// dependencies are free). A new crate or a new edge needs a line here, checked against
/// ARCHITECTURE.md.
const ALLOWED: &[(&str, &[&str])] = &[
    // No threads, no I/O, nothing else of Mocu; the compiler may use it.
    ("mocu-value", &[]),
    // The DataServer depends on nothing of ours but mocu-value.
    ("mocu-dataserver", &["mocu-value"]),
    // The compiler: the language, the JIT (knows nothing of the syntax tree), the lowering.
    ("mocu-language", &["mocu-value"]),
    ("mocu-jit", &[]),
    ("mocu-lower", &["mocu-value", "mocu-language", "mocu-jit"]),
    // Modules talk only through the DataServer.
    ("mocu-host", &["mocu-value", "mocu-dataserver"]),
    ("mocu-sim", &["mocu-value", "mocu-dataserver", "mocu-host"]),
    ("mocu-mavlink", &["mocu-value", "mocu-dataserver", "mocu-host"]),
    ("mocu-input", &["mocu-value", "mocu-dataserver", "mocu-host"]),
    ("mocu-mapdata", &["mocu-value", "mocu-dataserver", "mocu-host"]),
    // Scripts (#js:, #rhai:, script modules) reach the OCU only through the DataServer's API,
    // as native modules do; the engines know nothing of the compiler or layouts.
    ("mocu-script", &["mocu-value", "mocu-dataserver", "mocu-host"]),
    // Replay writes the world model from a recording, as a protocol module would.
    ("mocu-replay", &["mocu-dataserver"]),
    // The recorder reads the DataServer's change feed; it knows no layout, renderer or module.
    ("mocu-record", &["mocu-value", "mocu-dataserver"]),
    // The window manager knows no painter and nothing of the compiler.
    ("mocu-display", &["mocu-value", "mocu-dataserver"]),
    // Video: a module and the video window's painter (sees only the display's Canvas).
    ("mocu-video", &["mocu-value", "mocu-dataserver", "mocu-host", "mocu-display"]),
    // A layout reaches the rest of the OCU only through the DataServer (its script actions
    // too: the engines see the DataServer's API only).
    (
        "mocu-layout",
        &[
            "mocu-value",
            "mocu-dataserver",
            "mocu-language",
            "mocu-jit",
            "mocu-lower",
            "mocu-script",
        ],
    ),
    // The widget renderer reads the display from root.display; never talks to a layout.
    // Its `widgets` and `map_view` are module kinds like the others (the module host).
    (
        "mocu-widgets",
        &[
            "mocu-value",
            "mocu-dataserver",
            "mocu-language",
            "mocu-jit",
            "mocu-lower",
            "mocu-display",
            "mocu-host",
        ],
    ),
    (
        "mocu-hotreload",
        &[
            "mocu-value",
            "mocu-dataserver",
            "mocu-language",
            "mocu-layout",
            "mocu-widgets",
            "mocu-display",
        ],
    ),
    // The language server: the checker's API over the editor's documents; nothing of the runtime.
    ("mocu-lsp", &["mocu-language"]),
    // The distributed world model: a module that reads the change feed and writes through
    // the DataServer's API (the DataServer knows nothing of it).
    ("mocu-distrib", &["mocu-dataserver", "mocu-host"]),
    // The command line puts everything together.
    (
        "mocu",
        &[
            "mocu-lsp",
            "mocu-value",
            "mocu-dataserver",
            "mocu-language",
            "mocu-jit",
            "mocu-lower",
            "mocu-host",
            "mocu-sim",
            "mocu-mavlink",
            "mocu-input",
            "mocu-mapdata",
            "mocu-display",
            "mocu-video",
            "mocu-layout",
            "mocu-widgets",
            "mocu-hotreload",
            "mocu-replay",
            "mocu-record",
            "mocu-distrib",
            "mocu-script",
        ],
    ),
];

/// What the compiler crates must not reach, even through other crates: graphics, windows,
/// gamepads, file watching, thread pools and async runtimes, and the runtime's crates.
const NOT_IN_THE_COMPILER: &[&str] = &[
    "wgpu",
    "winit",
    "gilrs",
    "notify",
    "tokio",
    "rayon",
    "crossbeam",
    "crossbeam-channel",
    "async-std",
    "threadpool",
    "mio",
    "tiny-skia",
    "mocu-dataserver",
    "mocu-display",
    "mocu-layout",
    "mocu-widgets",
    "mocu-host",
];

const COMPILER: &[&str] = &["mocu-language", "mocu-jit", "mocu-lower"];

#[test]
fn every_crate_depends_only_on_the_crates_of_ours_its_rule_allows() {
    let g = Graph::load();
    let mut errors = Vec::new();
    for krate in g.workspace() {
        let Some((_, allowed)) = ALLOWED.iter().find(|(n, _)| *n == krate) else {
            errors.push(format!("{krate}: no dependency rule (add it to ALLOWED)"));
            continue;
        };
        for dep in g.direct(&krate) {
            if g.is_workspace(&dep) && !allowed.contains(&dep.as_str()) {
                errors.push(format!("{krate} depends on {dep}, which its rule forbids"));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

#[test]
fn the_dataserver_depends_on_nothing_of_ours_but_mocu_value() {
    let g = Graph::load();
    let ours: BTreeSet<String> = g
        .transitive("mocu-dataserver")
        .into_iter()
        .filter(|d| g.is_workspace(d) && d != "mocu-value")
        .collect();
    assert!(ours.is_empty(), "mocu-dataserver reaches {ours:?}");
}

#[test]
fn the_widget_renderer_does_not_depend_on_the_layout() {
    let g = Graph::load();
    let t = g.transitive("mocu-widgets");
    assert!(!t.contains("mocu-layout"), "mocu-widgets reaches mocu-layout");
}

#[test]
fn the_compiler_knows_nothing_of_graphics_input_file_watching_or_threads() {
    let g = Graph::load();
    let mut errors = Vec::new();
    for krate in COMPILER {
        for dep in g.transitive(krate) {
            if NOT_IN_THE_COMPILER.contains(&dep.as_str()) {
                errors.push(format!("{krate} reaches {dep}: {}", g.path(krate, &dep).join(" → ")));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

#[test]
fn the_renderer_knows_nothing_of_the_compiler() {
    let g = Graph::load();
    let t = g.transitive("mocu-display");
    let bad: Vec<_> = COMPILER.iter().filter(|c| t.contains(**c)).collect();
    assert!(bad.is_empty(), "mocu-display reaches {bad:?}");
}

/// The crates whose `unsafe` is allowed (each block with a `// SAFETY:` line).
const UNSAFE_ALLOWED_UNDER: &str = "compiler/jit/";

#[test]
fn no_unsafe_code_outside_the_jit() {
    let mut errors = Vec::new();
    for f in rust_files() {
        if f.rel.starts_with(UNSAFE_ALLOWED_UNDER) {
            continue;
        }
        for (n, line) in code_only(&f.text).lines().enumerate() {
            if has_word(line, "unsafe") {
                errors.push(format!("{}:{}: unsafe outside compiler/jit", f.rel, n + 1));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

#[test]
fn every_unsafe_block_in_the_jit_says_why_it_is_sound() {
    let mut errors = Vec::new();
    for f in rust_files().into_iter().filter(|f| f.rel.starts_with(UNSAFE_ALLOWED_UNDER)) {
        let raw: Vec<&str> = f.text.lines().collect();
        for (n, line) in code_only(&f.text).lines().enumerate() {
            // Blocks and impls need a reason; `unsafe fn` declarations have `# Safety` docs.
            let needs = line.contains("unsafe {") || line.contains("unsafe impl");
            if needs && !safety_comment_above(&raw, n) {
                errors.push(format!("{}:{}: unsafe without a `// SAFETY:` line", f.rel, n + 1));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// `// SAFETY:` on the line itself or in the comment lines right above it.
fn safety_comment_above(lines: &[&str], n: usize) -> bool {
    if lines[n].contains("SAFETY:") {
        return true;
    }
    lines[..n]
        .iter()
        .rev()
        .take_while(|l| l.trim_start().starts_with("//"))
        .any(|l| l.contains("SAFETY:"))
}

#[test]
fn every_crate_but_the_jit_forbids_unsafe_code() {
    let root = workspace_root();
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).expect("Cargo.toml");
    assert!(
        manifest.contains("[workspace.lints.rust]\nunsafe_code = \"forbid\""),
        "the workspace forbids unsafe_code in [workspace.lints.rust]"
    );
    let g = Graph::load();
    let mut errors = Vec::new();
    for p in g.packages.iter().filter(|p| p.name != "mocu-jit") {
        let text = std::fs::read_to_string(&p.manifest).unwrap_or_default();
        if !text.contains("[lints]\nworkspace = true") {
            errors.push(format!("{}: Cargo.toml lacks `[lints] workspace = true`", p.name));
        }
        for root_file in &p.roots {
            let text = std::fs::read_to_string(root_file).unwrap_or_default();
            if !text.contains("#![forbid(unsafe_code)]") {
                errors.push(format!("{}: no #![forbid(unsafe_code)]", root_file.display()));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// What reads files or the environment; only `compiler/language/src/fs.rs` may.
const FILE_SYSTEM: &[&str] = &[
    "std::fs",
    "std::env::var",
    "env::var(",
    "File::open",
    "File::create",
    "OpenOptions",
    "read_dir(",
    "stdin()",
];

#[test]
fn the_compiler_reads_files_only_in_fs_rs() {
    let mut errors = Vec::new();
    for f in rust_files() {
        let compiler_src = f.rel.starts_with("compiler/") && f.rel.contains("/src/");
        if !compiler_src || f.rel == "compiler/language/src/fs.rs" {
            continue;
        }
        for (n, line) in code_only(&f.text).lines().enumerate() {
            if let Some(p) = FILE_SYSTEM.iter().find(|p| line.contains(**p)) {
                errors.push(format!("{}:{}: `{p}` outside fs.rs", f.rel, n + 1));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// A test waits on a channel, a notification or a clock it advances, never by sleeping.
#[test]
fn no_test_sleeps_to_wait_for_time() {
    let mut errors = Vec::new();
    for f in rust_files().into_iter().filter(|f| is_test_file(&f.rel)) {
        for (n, line) in code_only(&f.text).lines().enumerate() {
            if line.contains("sleep(") {
                errors.push(format!("{}:{}: a test sleeps", f.rel, n + 1));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// Timings belong in benches/ (criterion, against a baseline); a test checks what happened,
/// and in which order, on a clock it controls.
#[test]
fn no_test_asserts_a_wall_clock_bound() {
    let mut errors = Vec::new();
    for f in rust_files().into_iter().filter(|f| is_test_file(&f.rel)) {
        let code = code_only(&f.text);
        for (at, arg) in assertions(&code) {
            if arg.contains("elapsed") || arg.contains("Instant") {
                let line = code[..at].lines().count().max(1);
                errors.push(format!("{}:{line}: an assertion on the wall clock", f.rel));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

#[test]
fn ignored_tests_say_why() {
    let mut errors = Vec::new();
    for f in rust_files() {
        for (n, line) in code_only(&f.text).lines().enumerate() {
            if line.contains("#[ignore]") {
                errors.push(format!("{}:{}: #[ignore] without `= \"reason\"`", f.rel, n + 1));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

const MAX_LINES: usize = 800;

/// Source files over [`MAX_LINES`] today.
const LONG_FILES: &[&str] = &[];

#[test]
fn no_source_file_is_over_800_lines() {
    let errors: Vec<String> = rust_files()
        .into_iter()
        .filter(|f| !LONG_FILES.contains(&f.rel.as_str()))
        .filter(|f| f.text.lines().count() > MAX_LINES)
        .map(|f| format!("{}: {} lines (at most {MAX_LINES})", f.rel, f.text.lines().count()))
        .collect();
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

fn is_test_file(rel: &str) -> bool {
    rel.starts_with("tests/") || rel.contains("/tests/")
}

fn has_word(line: &str, word: &str) -> bool {
    line.match_indices(word).any(|(i, _)| {
        let before = line[..i].chars().next_back();
        let after = line[i + word.len()..].chars().next();
        let ident = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
        !ident(before) && !ident(after)
    })
}

/// Every `assert…!(…)` / `prop_assert…!(…)` in code: its offset and its arguments' text.
fn assertions(code: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    for (at, _) in code.match_indices("assert") {
        let rest = &code[at..];
        let Some(bang) = rest.find('!') else { continue };
        let name = &rest[..bang];
        if !name.chars().all(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let args = &rest[bang + 1..];
        let Some(open) = args.chars().next().filter(|c| "([{".contains(*c)) else { continue };
        let close = match open {
            '(' => ')',
            '[' => ']',
            _ => '}',
        };
        let mut depth = 0;
        for (i, c) in args.char_indices() {
            if c == open {
                depth += 1;
            } else if c == close {
                depth -= 1;
                if depth == 0 {
                    out.push((at, &args[..=i]));
                    break;
                }
            }
        }
    }
    out
}

#[test]
fn the_scanner_sees_code_but_not_comments_strings_or_characters() {
    let src = "let a = \"unsafe\"; // unsafe\n/* unsafe /* nested */ */ let b = r#\"un\"safe\"#;\nlet c = '\"'; fn f<'a>(x: &'a u8) { unsafe_fn(); unsafe { } }\n";
    let code = code_only(src);
    assert_eq!(code.lines().count(), src.lines().count(), "line breaks kept");
    let hits: Vec<usize> = code
        .lines()
        .enumerate()
        .filter(|(_, l)| has_word(l, "unsafe"))
        .map(|(n, _)| n + 1)
        .collect();
    assert_eq!(hits, [3], "only the real block on line 3: {code}");
    assert!(code.contains("fn f<'a>(x: &'a u8)"), "lifetimes are code");
}

#[test]
fn wall_clock_assertions_are_found_through_their_arguments() {
    let code = "assert!(t0.elapsed() < d, \"x\");\nassert_eq!(a, b);\nprop_assert!(Instant::now() < end);\n";
    let found: Vec<&str> = assertions(code).into_iter().map(|(_, a)| a).collect();
    assert_eq!(found, ["(t0.elapsed() < d, \"x\")", "(a, b)", "(Instant::now() < end)"]);
}
