//! Parsing with reuse, for a front end that checks the same files again and again (the
//! language server: a keystroke at a time).
//!
//! The parser cuts a file into top-level items by brace depth and parses each on its own
//! ([`parser::split_items`]); an item's tree depends only on its text and where it starts. So
//! an [`ItemCache`] keeps the trees of the last check, keyed by their items' texts: the next
//! parse of a file takes the tree of every item whose text it has seen (moved, not copied, and
//! its spans shifted to where the item is now) and parses only the items that changed. A
//! keystroke in a 10,000-line layout parses one item, not 4,000.
//!
//! The result is the parser's, exactly (`parse_with_reuse_equals_the_parser` below, over every
//! layout of the repository and edits of them): what the cache cannot reproduce exactly it
//! hands to [`parser::parse`] whole. That is a file with a lexical problem (an unclosed string
//! or comment, a look-alike character) or an item whose braces never close or that is no item
//! (the parser's recovery looks across items there); an item with a syntax error is parsed in
//! place (its message may count lines of the file) and not kept.
//!
//! The files a layout `use`s (the standard library) are parsed through the same cache, so an
//! unchanged file costs a cut and a hash of its items.

use crate::ast::*;
use crate::diagnostics::Diagnostics;
use crate::parser::{self, ChunkKind};
use crate::passes::Modules;
use crate::passes::load_sources::load_sources_with;
use crate::source::{FileId, SourceLoader, SourceMap, Span};
use crate::{Config, Program, Schema};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Checks after which a tree nobody took is dropped (a document closed, an item deleted).
const KEEP_ROUNDS: u64 = 32;

/// The trees of earlier parses, by item text. See the module documentation.
#[derive(Default)]
pub struct ItemCache {
    /// Trees ready to be taken, by their item's text.
    trees: HashMap<String, Slot, BuildHasherDefault<Fx>>,
    /// Each file parsed with reuse: its items in order, to take their trees back afterwards.
    cuts: HashMap<String, Vec<Cut>>,
    /// Bumped by every [`ItemCache::load_sources`].
    round: u64,
    stats: Stats,
}

/// The trees of one item text.
#[derive(Default)]
struct Slot {
    trees: Vec<Tree>,
    /// The last round that took or gave back one of them.
    seen: u64,
}

/// The tree of one item text where it was last parsed.
struct Tree {
    start: u32,
    file: FileId,
    items: Vec<Item>,
}

/// One item of a file as the cache parsed it.
struct Cut {
    start: usize,
    end: usize,
    /// How many items of the tree it gave (0 or 1).
    items: usize,
    /// Whether its tree may be kept: it parsed without a diagnostic.
    keep: bool,
}

/// What the parses through a cache did, summed since it was made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Items whose earlier tree was taken.
    pub reused: usize,
    /// Items parsed.
    pub parsed: usize,
    /// Files handed to [`parser::parse`] whole.
    pub whole: usize,
}

impl ItemCache {
    pub fn new() -> ItemCache {
        ItemCache::default()
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// [`crate::compile_layout`], parsing through the cache; the trees go back to it after.
    #[allow(clippy::too_many_arguments)]
    pub fn compile_layout(
        &mut self,
        path: &str,
        text: String,
        loader: &dyn SourceLoader,
        schema: &Schema,
        config: &Config,
        sources: &mut SourceMap,
        diags: &mut Diagnostics,
    ) -> Program {
        let modules = self.load_sources(path, text, loader, sources, diags);
        let mut program = crate::compile_modules(&modules, schema, config, diags);
        crate::locate_scripts(&mut program, sources);
        self.recycle(modules, sources);
        program
    }

    /// Gives the trees of `modules` (from [`ItemCache::load_sources`], their texts in
    /// `sources`) back for the next parse.
    pub fn recycle(&mut self, modules: Modules, sources: &SourceMap) {
        for m in modules {
            let Some(cuts) = self.cuts.remove(&m.path) else { continue };
            if cuts.iter().map(|c| c.items).sum::<usize>() != m.ast.items.len() {
                continue;
            }
            let text = &sources.get(m.file).text;
            let mut items = m.ast.items.into_iter();
            for c in cuts {
                let tree: Vec<Item> = items.by_ref().take(c.items).collect();
                let Some(key) = text.get(c.start..c.end).filter(|_| c.keep) else { continue };
                let tree = Tree { start: c.start as u32, file: m.file, items: tree };
                match self.trees.get_mut(key) {
                    Some(slot) => {
                        slot.trees.push(tree);
                        slot.seen = self.round;
                    }
                    None => {
                        let slot = Slot { trees: vec![tree], seen: self.round };
                        self.trees.insert(key.to_string(), slot);
                    }
                }
            }
        }
    }

    /// [`parser::parse`] of `text` (the file `file` at `path`), reusing the trees of its items
    /// that were seen before.
    pub fn parse(&mut self, path: &str, file: FileId, text: &str, diags: &mut Diagnostics) -> File {
        let mut lexical = Diagnostics::new();
        let scan = crate::lexer::scan(file, text, &mut lexical);
        let chunks = parser::split_items(text);
        if !lexical.is_empty()
            || !scan.broken.is_empty()
            || chunks.iter().any(|c| c.kind != ChunkKind::Item)
        {
            self.cuts.remove(path);
            self.stats.whole += 1;
            return parser::parse(file, text, diags);
        }
        let mut items = Vec::new();
        let mut cuts = Vec::with_capacity(chunks.len());
        for chunk in &chunks {
            let src = &text[chunk.start..chunk.end];
            let before = items.len();
            let mut keep = true;
            let round = self.round;
            let reused = self.trees.get_mut(src).and_then(|slot| {
                slot.seen = round;
                slot.trees.pop()
            });
            if let Some(mut tree) = reused {
                let delta = chunk.start as i64 - i64::from(tree.start);
                if delta != 0 || tree.file != file {
                    for item in &mut tree.items {
                        item.shift(delta, file);
                    }
                }
                items.append(&mut tree.items);
                self.stats.reused += 1;
            } else {
                self.stats.parsed += 1;
                match parse_alone(file, src) {
                    Some(mut alone) => {
                        for item in &mut alone {
                            item.shift(chunk.start as i64, file);
                        }
                        items.append(&mut alone);
                    }
                    None => {
                        keep = false;
                        items.extend(parse_in_place(file, text, chunk.start, src, diags));
                    }
                }
            }
            cuts.push(Cut {
                start: chunk.start,
                end: chunk.end,
                items: items.len() - before,
                keep,
            });
        }
        self.cuts.insert(path.to_string(), cuts);
        File { items }
    }

    /// [`crate::passes::load_sources::load_sources`], parsing through the cache.
    pub fn load_sources(
        &mut self,
        path: &str,
        text: String,
        loader: &dyn SourceLoader,
        sources: &mut SourceMap,
        diags: &mut Diagnostics,
    ) -> Modules {
        self.round += 1;
        let round = self.round;
        self.trees.retain(|_, slot| slot.seen + KEEP_ROUNDS >= round);
        load_sources_with(path, text, loader, sources, diags, &mut |path, file, text, diags| {
            self.parse(path, file, text, diags)
        })
    }
}

/// The items of one item text parsed as a file of its own (spans from 0), when that is what
/// the parser gives it inside its file: it is one item and parses without a diagnostic.
fn parse_alone(file: FileId, src: &str) -> Option<Vec<Item>> {
    let mut diags = Diagnostics::new();
    let tree = parser::parse(file, src, &mut diags);
    let one =
        matches!(parser::split_items(src).as_slice(), [c] if c.start == 0 && c.end == src.len());
    (diags.is_empty() && one).then_some(tree.items)
}

/// The items of the item text `src` at `start` in `text`, parsed where it stands (the text
/// before it blanked, its line breaks kept), its diagnostics reported as the parser words
/// them in the whole file.
fn parse_in_place(
    file: FileId,
    text: &str,
    start: usize,
    src: &str,
    diags: &mut Diagnostics,
) -> Vec<Item> {
    let mut blanked: String =
        text[..start].bytes().map(|b| if b == b'\n' { '\n' } else { ' ' }).collect();
    // Bytes, not characters, are blanked: offsets stay those of the file.
    blanked.push_str(src);
    parser::parse(file, &blanked, diags).items
}

/// Fx, rustc's hash: item texts are hashed twice a check, and SipHash (std's) was a tenth of
/// a warm parse.
#[derive(Default)]
struct Fx(u64);

impl Hasher for Fx {
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.add(u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]));
        }
        for &b in chunks.remainder() {
            self.add(u64::from(b));
        }
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

impl Fx {
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// Moving a tree: every span `delta` bytes on, into `file`. Each node is taken apart whole
/// (no `..`), so a span added to the syntax tree cannot be missed here.
trait Shift {
    fn shift(&mut self, delta: i64, file: FileId);
}

impl Shift for Span {
    fn shift(&mut self, delta: i64, file: FileId) {
        self.file = file;
        self.start = (i64::from(self.start) + delta) as u32;
        self.end = (i64::from(self.end) + delta) as u32;
    }
}

impl<T: Shift> Shift for Vec<T> {
    fn shift(&mut self, delta: i64, file: FileId) {
        for x in self {
            x.shift(delta, file);
        }
    }
}

impl<T: Shift> Shift for Option<T> {
    fn shift(&mut self, delta: i64, file: FileId) {
        if let Some(x) = self {
            x.shift(delta, file);
        }
    }
}

impl<T: Shift> Shift for Box<T> {
    fn shift(&mut self, delta: i64, file: FileId) {
        (**self).shift(delta, file);
    }
}

impl<A: Shift, B: Shift> Shift for (A, B) {
    fn shift(&mut self, delta: i64, file: FileId) {
        self.0.shift(delta, file);
        self.1.shift(delta, file);
    }
}

/// What carries no span.
impl Shift for String {
    fn shift(&mut self, _: i64, _: FileId) {}
}

impl Shift for Ident {
    fn shift(&mut self, d: i64, f: FileId) {
        let Ident { name: _, span } = self;
        span.shift(d, f);
    }
}

impl Shift for Item {
    fn shift(&mut self, d: i64, f: FileId) {
        match self {
            Item::Use(Use { path: _, path_span, alias, span }) => {
                path_span.shift(d, f);
                alias.shift(d, f);
                span.shift(d, f);
            }
            Item::Let(l) => l.shift(d, f),
            Item::Window(Window { name, rect, anchor, props, span }) => {
                name.shift(d, f);
                rect.shift(d, f);
                anchor.shift(d, f);
                props.shift(d, f);
                span.shift(d, f);
            }
            Item::In(InBlock { window, widgets, span }) => {
                window.shift(d, f);
                widgets.shift(d, f);
                span.shift(d, f);
            }
            Item::Component(Component { name, params, body, span }) => {
                name.shift(d, f);
                params.shift(d, f);
                body.shift(d, f);
                span.shift(d, f);
            }
            Item::Bind(Bind { device, shift, bindings, modes, span }) => {
                device.shift(d, f);
                shift.shift(d, f);
                bindings.shift(d, f);
                modes.shift(d, f);
                span.shift(d, f);
            }
            Item::Menu(Menu { object_type: _, type_span, entries, span }) => {
                type_span.shift(d, f);
                entries.shift(d, f);
                span.shift(d, f);
            }
            Item::Watch(w) => {
                let Watch { name, when, hold, clear, repeat, actions, span } = &mut **w;
                name.shift(d, f);
                when.shift(d, f);
                hold.shift(d, f);
                clear.shift(d, f);
                repeat.shift(d, f);
                actions.shift(d, f);
                span.shift(d, f);
            }
            Item::Each(e) => {
                let Each { var, source, object_type, flow, items, span } = &mut **e;
                var.shift(d, f);
                source.shift(d, f);
                object_type.shift(d, f);
                if let Some(Flow { direction, rect, anchor, gap, span }) = flow {
                    direction.shift(d, f);
                    rect.shift(d, f);
                    anchor.shift(d, f);
                    gap.shift(d, f);
                    span.shift(d, f);
                }
                items.shift(d, f);
                span.shift(d, f);
            }
            Item::Design(Design { width, height, span }) => {
                width.shift(d, f);
                height.shift(d, f);
                span.shift(d, f);
            }
        }
    }
}

impl Shift for Let {
    fn shift(&mut self, d: i64, f: FileId) {
        let Let { name, value, span } = self;
        name.shift(d, f);
        value.shift(d, f);
        span.shift(d, f);
    }
}

impl Shift for Prop {
    fn shift(&mut self, d: i64, f: FileId) {
        let Prop { name, value, span } = self;
        name.shift(d, f);
        value.shift(d, f);
        span.shift(d, f);
    }
}

impl Shift for Widget {
    fn shift(&mut self, d: i64, f: FileId) {
        let Widget { name, component, at, anchor, args, handlers, span } = self;
        name.shift(d, f);
        component.shift(d, f);
        at.shift(d, f);
        anchor.shift(d, f);
        args.shift(d, f);
        handlers.shift(d, f);
        span.shift(d, f);
    }
}

impl Shift for Handler {
    fn shift(&mut self, d: i64, f: FileId) {
        let Handler { event, actions, span } = self;
        event.shift(d, f);
        actions.shift(d, f);
        span.shift(d, f);
    }
}

impl Shift for Param {
    fn shift(&mut self, d: i64, f: FileId) {
        match self {
            Param::Value { name, ty, default } => {
                name.shift(d, f);
                if let Some(TypeName { name, optional: _ }) = ty {
                    name.shift(d, f);
                }
                default.shift(d, f);
            }
            Param::Event { name } => name.shift(d, f),
        }
    }
}

impl Shift for Stmt {
    fn shift(&mut self, d: i64, f: FileId) {
        match self {
            Stmt::Let(l) => l.shift(d, f),
            Stmt::Primitive(Primitive { kind, args, styles, span }) => {
                kind.shift(d, f);
                args.shift(d, f);
                styles.shift(d, f);
                span.shift(d, f);
            }
        }
    }
}

impl Shift for Binding {
    fn shift(&mut self, d: i64, f: FileId) {
        let Binding { shift: _, kind, input, options, actions, span } = self;
        kind.shift(d, f);
        input.shift(d, f);
        options.shift(d, f);
        actions.shift(d, f);
        span.shift(d, f);
    }
}

impl Shift for BindingOption {
    fn shift(&mut self, d: i64, f: FileId) {
        let BindingOption { name, value, span } = self;
        name.shift(d, f);
        value.shift(d, f);
        span.shift(d, f);
    }
}

impl Shift for MenuEntry {
    fn shift(&mut self, d: i64, f: FileId) {
        let MenuEntry { label, enabled, actions, span } = self;
        label.shift(d, f);
        enabled.shift(d, f);
        actions.shift(d, f);
        span.shift(d, f);
    }
}

impl Shift for Action {
    fn shift(&mut self, d: i64, f: FileId) {
        let Action { kind, span } = self;
        span.shift(d, f);
        match kind {
            ActionKind::Set { target, value } => {
                target.shift(d, f);
                value.shift(d, f);
            }
            ActionKind::Call { call } => call.shift(d, f),
            ActionKind::Swap { a, b, duration } => {
                a.shift(d, f);
                b.shift(d, f);
                duration.shift(d, f);
            }
            ActionKind::Show { window } | ActionKind::Hide { window } => window.shift(d, f),
            ActionKind::Alert { level, message } => {
                level.shift(d, f);
                message.shift(d, f);
            }
            ActionKind::Mode { mode } => mode.shift(d, f),
            ActionKind::Select { target } => match target {
                SelectTarget::Next | SelectTarget::Prev => {}
                SelectTarget::Object(e) => e.shift(d, f),
            },
            ActionKind::Script { engine, body: _, body_span } => {
                engine.shift(d, f);
                body_span.shift(d, f);
            }
        }
    }
}

impl Shift for Expr {
    fn shift(&mut self, d: i64, f: FileId) {
        let Expr { kind, span } = self;
        span.shift(d, f);
        match kind {
            ExprKind::Number { .. }
            | ExprKind::Colour(_)
            | ExprKind::Bool(_)
            | ExprKind::Name(_)
            | ExprKind::SelfRef
            | ExprKind::Error => {}
            ExprKind::Str(parts) => {
                for p in parts {
                    match p {
                        StrPart::Text(_) => {}
                        StrPart::Interp { expr, spec } => {
                            expr.shift(d, f);
                            spec.shift(d, f);
                        }
                    }
                }
            }
            ExprKind::Field(e, name) => {
                e.shift(d, f);
                name.shift(d, f);
            }
            ExprKind::Index(e, _) => e.shift(d, f),
            ExprKind::Call(callee, args) => {
                callee.shift(d, f);
                args.shift(d, f);
            }
            ExprKind::Unary(_, e) => e.shift(d, f),
            ExprKind::Binary(_, a, b) => {
                a.shift(d, f);
                b.shift(d, f);
            }
            ExprKind::If(c, a, b) => {
                c.shift(d, f);
                a.shift(d, f);
                b.shift(d, f);
            }
        }
    }
}
