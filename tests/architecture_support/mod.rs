//! What the architecture tests read: the dependency graph from `cargo metadata`, and the
//! workspace's Rust sources with comments and literals blanked out.

use serde_json::Value as Json;
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};
use std::process::Command;

pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A workspace package: its name, manifest and crate roots (its library's and binaries'
/// main files).
pub struct Package {
    pub name: String,
    pub manifest: PathBuf,
    pub roots: Vec<PathBuf>,
}

/// The resolved dependency graph, normal and build edges only (dev edges are free).
pub struct Graph {
    pub packages: Vec<Package>,
    /// Package name → names of its normal and build dependencies.
    edges: BTreeMap<String, BTreeSet<String>>,
}

impl Graph {
    pub fn load() -> Graph {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.args(["metadata", "--format-version", "1"]).current_dir(workspace_root());
        if let Some(host) = host_triple() {
            cmd.args(["--filter-platform", &host]);
        }
        let out = cmd.output().expect("runs cargo metadata");
        assert!(out.status.success(), "cargo metadata: {}", String::from_utf8_lossy(&out.stderr));
        let m: Json = serde_json::from_slice(&out.stdout).expect("cargo metadata gives JSON");
        let members: BTreeSet<&str> = m["workspace_members"]
            .as_array()
            .expect("members")
            .iter()
            .filter_map(Json::as_str)
            .collect();
        let mut names = BTreeMap::new();
        let mut packages = Vec::new();
        for p in m["packages"].as_array().expect("packages") {
            let id = p["id"].as_str().unwrap_or_default();
            let name = p["name"].as_str().unwrap_or_default().to_string();
            names.insert(id.to_string(), name.clone());
            if members.contains(id) {
                let roots = p["targets"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter(|t| {
                        let kinds = t["kind"].as_array().into_iter().flatten();
                        kinds.filter_map(Json::as_str).any(|k| k == "lib" || k == "bin")
                    })
                    .filter_map(|t| t["src_path"].as_str().map(PathBuf::from))
                    .collect();
                let manifest = PathBuf::from(p["manifest_path"].as_str().unwrap_or_default());
                packages.push(Package { name, manifest, roots });
            }
        }
        let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for node in m["resolve"]["nodes"].as_array().expect("resolve") {
            let from = names[node["id"].as_str().unwrap_or_default()].clone();
            let entry = edges.entry(from).or_default();
            for d in node["deps"].as_array().into_iter().flatten() {
                let kinds = d["dep_kinds"].as_array().into_iter().flatten();
                let runtime = kinds.map(|k| &k["kind"]).any(|k| k.is_null() || k == "build");
                if runtime {
                    entry.insert(names[d["pkg"].as_str().unwrap_or_default()].clone());
                }
            }
        }
        Graph { packages, edges }
    }

    pub fn workspace(&self) -> Vec<String> {
        self.packages.iter().map(|p| p.name.clone()).collect()
    }

    pub fn is_workspace(&self, name: &str) -> bool {
        self.packages.iter().any(|p| p.name == name)
    }

    pub fn direct(&self, name: &str) -> BTreeSet<String> {
        self.edges.get(name).cloned().unwrap_or_default()
    }

    /// Everything `name` reaches through normal and build dependencies.
    pub fn transitive(&self, name: &str) -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut todo: Vec<String> = self.direct(name).into_iter().collect();
        while let Some(n) = todo.pop() {
            if seen.insert(n.clone()) {
                todo.extend(self.direct(&n));
            }
        }
        seen
    }

    /// A shortest dependency path from `from` to `to`, for the failure message.
    pub fn path(&self, from: &str, to: &str) -> Vec<String> {
        let mut back: BTreeMap<String, String> = BTreeMap::new();
        let mut queue = VecDeque::from([from.to_string()]);
        while let Some(n) = queue.pop_front() {
            if n == to {
                let mut path = vec![n.clone()];
                let mut at = n;
                while let Some(p) = back.get(&at) {
                    path.push(p.clone());
                    at = p.clone();
                }
                path.reverse();
                return path;
            }
            for d in self.direct(&n) {
                if d != from && !back.contains_key(&d) {
                    back.insert(d.clone(), n.clone());
                    queue.push_back(d);
                }
            }
        }
        vec![from.to_string(), to.to_string()]
    }
}

fn host_triple() -> Option<String> {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let out = Command::new(rustc).arg("-vV").output().ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    text.lines().find_map(|l| l.strip_prefix("host: ")).map(str::to_string)
}

/// A Rust source of the workspace.
pub struct SourceFile {
    /// Path from the workspace root, with `/`.
    pub rel: String,
    pub text: String,
}

/// Every `.rs` file under the workspace root but build output, hidden folders and folders
/// of other repositories.
pub fn rust_files() -> Vec<SourceFile> {
    let root = workspace_root();
    let mut out = Vec::new();
    let mut todo = vec![root.clone()];
    while let Some(dir) = todo.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for e in entries.flatten() {
            let path = e.path();
            let name = e.file_name().to_string_lossy().to_string();
            if path.is_dir() {
                // vendor/ holds third-party code (patched crates, see vendor/*/PATCHED.md): it
                // is not held to our rules.
                let third_party = dir == root && name == "vendor";
                let skip = name.starts_with('.')
                    || name == "target"
                    || name == "node_modules"
                    || third_party;
                if !skip {
                    todo.push(path);
                }
            } else if name.ends_with(".rs") {
                let Ok(text) = std::fs::read_to_string(&path) else { continue };
                out.push(SourceFile { rel: rel(&root, &path), text });
            }
        }
    }
    out.sort_by(|a, b| a.rel.cmp(&b.rel));
    out
}

fn rel(root: &Path, path: &Path) -> String {
    path.strip_prefix(root).unwrap_or(path).to_string_lossy().replace('\\', "/")
}

/// The source with comments and the contents of string and character literals replaced by
/// spaces (line breaks kept, so line numbers still hold).
pub fn code_only(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if let Some(hashes) = raw_string_start(&c, i) {
            // r"…", r#"…"#, br"…": up to the quote followed by as many hashes.
            let open = c[i..].iter().position(|&x| x == '"').unwrap_or(0) + i;
            out.extend(std::iter::repeat_n(' ', open + 1 - i));
            i = open + 1;
            while i < c.len() {
                let closes = c[i] == '"' && (0..hashes).all(|k| c.get(i + 1 + k) == Some(&'#'));
                if closes {
                    out.extend(std::iter::repeat_n(' ', hashes + 1));
                    i += hashes + 1;
                    break;
                }
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '"' {
            out.push(' ');
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    blank(&mut out, c[i]);
                    i += 1;
                }
                if i < c.len() {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c[i] == '\'' && is_char_literal(&c, i) {
            out.push(' ');
            i += 1;
            while i < c.len() && c[i] != '\'' {
                if c[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                out.push(' ');
                i += 1;
            }
            out.push(' ');
            i += 1;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// At `i`, a raw string starts (`r"`, `r#"`, `br"`, not inside an identifier): its hashes.
fn raw_string_start(c: &[char], i: usize) -> Option<usize> {
    let ident_before = i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
    let start = match c[i] {
        'r' => i + 1,
        'b' if c.get(i + 1) == Some(&'r') => i + 2,
        _ => return None,
    };
    if ident_before {
        return None;
    }
    let hashes = c[start..].iter().take_while(|&&x| x == '#').count();
    (c.get(start + hashes) == Some(&'"')).then_some(hashes)
}

/// A `'` that opens a character literal (`'a'`, `'\n'`, `'\u{1F600}'`), not a lifetime.
fn is_char_literal(c: &[char], i: usize) -> bool {
    match c.get(i + 1) {
        Some('\\') => true,
        Some(_) => c.get(i + 2) == Some(&'\''),
        None => false,
    }
}
