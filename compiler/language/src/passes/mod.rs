//! The checks, one file each, run in order by [`crate::compile_layout`]. Every pass takes
//! `&mut Diagnostics` and reports instead of stopping.

pub mod check_anchors;
pub mod check_depth;
pub mod check_durations;
pub mod check_method_args;
pub mod check_paths;
pub mod check_schema;
pub mod check_scripts;
pub mod check_types;
pub mod collect_definitions;
pub mod load_sources;
pub mod resolve_names;
pub mod warn_constant_watch;
pub mod warn_outside_window;
pub mod warn_unused;

use crate::ast;
use crate::diagnostics::Diagnostics;
use crate::program::Program;
use crate::schema::Schema;
use crate::source::FileId;
use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// The passes over the typed program that look at each of its parts on its own (so that
/// `crate::lint` runs them on a batch's program too): schema rules (they need complete,
/// typed paths, after `let`s are inlined), method arguments, depth once `let`s are put in
/// place, screen px in a design, constant watches.
pub fn check_program(program: &Program, schema: &Schema, diags: &mut Diagnostics) {
    check_schema::check_schema(program, schema, diags);
    check_method_args::check_method_args(program, schema, diags);
    check_depth::check_depth(program, diags);
    check_anchors::warn_screen_px(program, diags);
    warn_constant_watch::warn_constant_watch(program, diags);
}

/// A hash map for the checker's own tables, keyed by names, spans and pointers: hashed with
/// [`FastHasher`] (no defence against chosen collisions is needed for a layout's names,
/// and SipHash was a tenth of the checker's time).
pub type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;
/// A hash set hashed with [`FastHasher`].
pub type FastSet<T> = HashSet<T, BuildHasherDefault<FastHasher>>;

/// The Fx hash (rustc's): a rotate, an xor and a multiply per word.
#[derive(Clone, Copy, Default)]
pub struct FastHasher(u64);

impl FastHasher {
    const K: u64 = 0xf135_7aea_2e62_a9c5;
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(Self::K);
    }
}

impl Hasher for FastHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.add(u64::from_le_bytes(c.try_into().unwrap_or_default()));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut last = [0u8; 8];
            last[..rest.len()].copy_from_slice(rest);
            self.add(u64::from_le_bytes(last));
        }
    }
    fn write_u8(&mut self, i: u8) {
        self.add(u64::from(i));
    }
    fn write_u32(&mut self, i: u32) {
        self.add(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }
    fn finish(&self) -> u64 {
        // The low bits pick the bucket: fold the well-mixed high bits down.
        self.0.rotate_left(26)
    }
}

/// Index of a loaded file in a [`Modules`] list; 0 is the layout being checked.
pub type ModuleId = usize;

/// One parsed file and the files its `use`s point to.
#[derive(Debug)]
pub struct Module {
    pub file: FileId,
    pub path: String,
    pub ast: ast::File,
    pub uses: Vec<UseEdge>,
}

#[derive(Debug, Clone)]
pub struct UseEdge {
    pub target: ModuleId,
    pub alias: Option<String>,
}

pub type Modules = Vec<Module>;

/// Where a top-level `let`, component or window is defined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DefId {
    pub module: ModuleId,
    /// Index of the item in the module's items (for template contents: of the `for each`).
    pub item: usize,
    /// Index inside a `for each` body, when there.
    pub inner: Option<usize>,
}

/// The top-level names of every module.
#[derive(Debug, Default)]
pub struct Definitions {
    pub lets: Vec<FastMap<String, DefId>>,
    pub components: Vec<FastMap<String, DefId>>,
    pub windows: Vec<FastMap<String, DefId>>,
}

impl Definitions {
    /// A top-level `let` visible from `module` (its own, then unqualified uses), defined
    /// before item `limit` when looking from inside another `let`.
    pub fn find_let(
        &self,
        modules: &Modules,
        module: ModuleId,
        name: &str,
        limit: Option<usize>,
    ) -> Option<DefId> {
        if let Some(d) = self.lets[module].get(name)
            && limit.is_none_or(|l| d.item < l)
        {
            return Some(*d);
        }
        modules[module]
            .uses
            .iter()
            .filter(|u| u.alias.is_none())
            .find_map(|u| self.lets[u.target].get(name).copied())
    }
    pub fn find_component(&self, modules: &Modules, module: ModuleId, name: &str) -> Option<DefId> {
        self.components[module]
            .get(name)
            .or_else(|| {
                modules[module].uses.iter().find_map(|u| self.components[u.target].get(name))
            })
            .copied()
    }
    /// Windows are shared by a layout and the files it uses.
    pub fn find_window(&self, modules: &Modules, module: ModuleId, name: &str) -> Option<DefId> {
        self.windows[module]
            .get(name)
            .or_else(|| modules[module].uses.iter().find_map(|u| self.windows[u.target].get(name)))
            .copied()
    }
    pub fn namespace(&self, modules: &Modules, module: ModuleId, name: &str) -> Option<ModuleId> {
        modules[module].uses.iter().find(|u| u.alias.as_deref() == Some(name)).map(|u| u.target)
    }
    /// Every name visible from `module`, for "did you mean".
    pub fn visible_names(&self, modules: &Modules, module: ModuleId) -> Vec<String> {
        let mut out: Vec<String> = self.lets[module].keys().cloned().collect();
        for u in &modules[module].uses {
            match &u.alias {
                None => out.extend(self.lets[u.target].keys().cloned()),
                Some(a) => out.push(a.clone()),
            }
        }
        out.push("root".into());
        out
    }
    pub fn visible_components(&self, modules: &Modules, module: ModuleId) -> Vec<String> {
        let mut out: Vec<String> = self.components[module].keys().cloned().collect();
        for u in &modules[module].uses {
            out.extend(self.components[u.target].keys().cloned());
        }
        out.extend(crate::builtins::NATIVES.iter().map(|n| n.name.to_string()));
        out
    }
    pub fn visible_windows(&self, modules: &Modules, module: ModuleId) -> Vec<String> {
        let mut out: Vec<String> = self.windows[module].keys().cloned().collect();
        for u in &modules[module].uses {
            out.extend(self.windows[u.target].keys().cloned());
        }
        out
    }
}

/// Looks an item up by [`DefId`].
pub fn item(modules: &Modules, id: DefId) -> Option<&ast::Item> {
    let top = modules.get(id.module)?.ast.items.get(id.item)?;
    match (top, id.inner) {
        (ast::Item::Each(e), Some(i)) => e.items.get(i),
        (_, None) => Some(top),
        _ => None,
    }
}

pub fn let_item(modules: &Modules, id: DefId) -> Option<&ast::Let> {
    match item(modules, id)? {
        ast::Item::Let(l) => Some(l),
        _ => None,
    }
}

pub fn component_item(modules: &Modules, id: DefId) -> Option<&ast::Component> {
    match item(modules, id)? {
        ast::Item::Component(c) => Some(c),
        _ => None,
    }
}
