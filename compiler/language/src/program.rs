//! The checked program: what the compiler hands to the runtime. Every expression is typed and
//! carries its span; every bound expression lists its paths, which is its subscription set.
//! Names are resolved: a `let` is checked once and its uses refer to it ([`Node::Let`], see
//! [`Let`]), component parameters are [`Node::Param`], template variables and `self` are
//! path bases. This is what a bundle stores (serde; `let`s by number, see [`Lets`]).

use crate::ast::{BinOp, UnOp};
use crate::source::Span;
use crate::types::{Type, TypeKind};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::sync::Arc;

/// One checked layout file and everything it uses.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Program {
    /// Every `let` of the program, each checked once, in the order they were checked (a
    /// `let` reads only those before it). First, so that a bundle defines them before any
    /// use (see [`Lets`]).
    #[serde(default)]
    pub lets: Lets,
    /// The layout's path (as given), then the files it uses.
    pub files: Vec<String>,
    pub windows: Vec<Window>,
    pub widgets: Vec<Widget>,
    pub components: Vec<Component>,
    pub bindings: Vec<Binding>,
    pub menus: Vec<Menu>,
    pub watches: Vec<Watch>,
    pub templates: Vec<Template>,
    /// `design W x H` in the layout file (see [`crate::placement`]).
    #[serde(default)]
    pub design: Option<crate::placement::Design>,
}

/// An expression bound to the world model: its typed tree and the paths it reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bound {
    pub expr: Expr,
    /// The subscription set: every path the expression reads, once, in order of appearance.
    pub paths: Vec<Path>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Expr {
    pub ty: Type,
    pub node: Node,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Node {
    Number(f64),
    Bool(bool),
    Str(String),
    /// RGBA, 8 bits each.
    Colour(u32),
    /// Milliseconds.
    Duration(f64),
    Path(Path),
    /// The value of a `let`, checked once and shared by all its uses (its type is the
    /// value's). A `let` whose value is a path or a constant is copied instead.
    Let(LetRef),
    /// A component parameter (in a component body) or a sibling argument (in a widget).
    Param(String),
    /// The widget's width `w` or height `h` in a component body.
    Size(String),
    /// A binding's implicit value: `axis` or `delta`.
    Input(String),
    /// The 0-based position of a template instance.
    Index,
    /// `.min` / `.max` of a range.
    RangeEnd {
        range: Box<Expr>,
        max: bool,
    },
    Range {
        lo: Box<Expr>,
        hi: Box<Expr>,
    },
    Unary {
        op: UnOp,
        arg: Box<Expr>,
    },
    Binary {
        op: BinOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    If {
        cond: Box<Expr>,
        then: Box<Expr>,
        other: Box<Expr>,
    },
    Call {
        function: String,
        args: Vec<Expr>,
    },
    /// An interpolated string.
    Format(Vec<FormatPart>),
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FormatPart {
    Text(String),
    Value { expr: Expr, spec: Option<FormatSpec> },
}

/// `{x:03.1}`: zero padding, minimum width, digits after the point.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct FormatSpec {
    pub zero: bool,
    pub width: Option<u32>,
    pub precision: Option<u32>,
}

/// A dotted path: a base and property/object names. `root.vehicles["USV 1"].nav.speed`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Path {
    pub base: PathBase,
    pub segments: Vec<String>,
    /// The schema type of the base object, when known (for `self` and template variables).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_type: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PathBase {
    Root,
    /// `self` in a menu: the object the menu was opened on.
    SelfObject,
    /// A `for each` variable: one object per template instance.
    Var(String),
    /// A component parameter of type object.
    Param(String),
    /// `selected` in an action: the object whose GUID is in `root.operator.selected`.
    Selected,
}

impl fmt::Display for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.base {
            PathBase::Root => f.write_str("root")?,
            PathBase::SelfObject => f.write_str("self")?,
            PathBase::Var(v) | PathBase::Param(v) => f.write_str(v)?,
            PathBase::Selected => f.write_str("selected")?,
        }
        for s in &self.segments {
            if !s.is_empty()
                && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !s.starts_with(|c: char| c.is_ascii_digit())
            {
                write!(f, ".{s}")?;
            } else {
                write!(f, "[{s:?}]")?;
            }
        }
        Ok(())
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Window {
    pub name: String,
    /// The module that paints it: "layer" (widgets only), "video", "map", ….
    pub kind: String,
    pub layer: Bound,
    /// x, y, width, height; numbers in px, or with unit "%" of the screen.
    pub rect: Vec<Bound>,
    /// The screen's point `rect` is measured from (see [`crate::placement`]).
    #[serde(default)]
    pub anchor: crate::placement::Anchor,
    pub opacity: Bound,
    pub visible: Bound,
    pub source: Option<Bound>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Widget {
    pub name: Option<String>,
    pub window: String,
    pub component: String,
    /// Drawn by Rust (Video, Map, VehicleList) rather than by a component body.
    pub native: bool,
    /// x, y and optionally width, height in the window's px.
    pub at: Vec<Bound>,
    /// The window's point `at` is measured from (see [`crate::placement`]).
    #[serde(default)]
    pub anchor: crate::placement::Anchor,
    /// Every parameter of the component, defaults filled in.
    pub args: Vec<Arg>,
    pub visible: Option<Bound>,
    pub handlers: Vec<Handler>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Arg {
    pub name: String,
    pub value: Bound,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Handler {
    pub event: String,
    pub actions: Vec<Action>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Component {
    pub name: String,
    pub params: Vec<Param>,
    pub events: Vec<String>,
    pub shapes: Vec<Shape>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Param {
    pub name: String,
    pub ty: Type,
    pub default: Option<Bound>,
}

/// One drawing primitive: rect, rounded, circle, arc, line, polyline, text, image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Shape {
    pub kind: String,
    pub args: Vec<Bound>,
    pub styles: Vec<Arg>,
    pub span: Span,
}

/// One input binding: which input, on which event, shaped how, in which mode and layer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Binding {
    pub device: String,
    pub kind: String,
    pub input: String,
    /// `change` (axes, wheels), or `press`, `release`, `hold`, `double` (buttons, keys).
    #[serde(default = "change")]
    pub event: String,
    /// For `hold`: how long the input must be held, in milliseconds.
    #[serde(default)]
    pub hold_ms: f64,
    /// The mode the binding belongs to (`mode drive { … }`); `None`: every mode.
    #[serde(default)]
    pub mode: Option<String>,
    /// Written `shift …`: active only while the device's shift input is held.
    #[serde(default)]
    pub shift: bool,
    /// The device's shift input (`shift left_bumper` in its `bind` block), if any.
    #[serde(default)]
    pub shift_input: Option<String>,
    /// How an axis value is shaped before the actions see it.
    #[serde(default)]
    pub shaping: Shaping,
    pub actions: Vec<Action>,
    pub span: Span,
}

fn change() -> String {
    "change".into()
}

/// Axis shaping, applied in this order: invert, deadzone, expo, scale, rate limit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Shaping {
    /// Inputs within ±deadzone read 0; the rest is rescaled to reach ±1 (0..1).
    pub deadzone: f64,
    /// Blend of linear and cubic response: (1 − e)·x + e·x³ (0..1).
    pub expo: f64,
    pub scale: f64,
    pub invert: bool,
    /// Largest change of the shaped value per second (0: unlimited).
    pub rate: f64,
}

impl Default for Shaping {
    fn default() -> Shaping {
        Shaping { deadzone: 0.0, expo: 0.0, scale: 1.0, invert: false, rate: 0.0 }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Menu {
    pub object_type: String,
    pub items: Vec<MenuItem>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MenuItem {
    pub label: Bound,
    pub enabled: Option<Bound>,
    pub actions: Vec<Action>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Watch {
    pub name: String,
    pub when: Bound,
    /// How long `when` must hold before the actions run, in milliseconds.
    pub hold_ms: Option<f64>,
    /// `clear when C` (hysteresis): once fired, active until C holds (else until `when`
    /// stops holding).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clear: Option<Bound>,
    /// `repeat every T` (level triggering), in milliseconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeat_ms: Option<f64>,
    pub actions: Vec<Action>,
    pub span: Span,
}

/// `for each v in root.vehicles of type "usv" { … }`: instantiated once per matching child.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Template {
    pub var: String,
    /// The object whose children are iterated.
    pub source: Path,
    pub object_type: Option<String>,
    /// `flow …`: the runtime places each instance's windows in a region, one after another.
    #[serde(default)]
    pub flow: Option<Flow>,
    pub windows: Vec<Window>,
    pub widgets: Vec<Widget>,
    pub watches: Vec<Watch>,
    pub span: Span,
}

/// `flow down rect X Y W H anchor NAME gap N`: each instance's windows (as one block: the
/// box around them) are placed one after another in the region, down a column or along a
/// row, wrapping to the next when the next would leave it; those that do not fit are hidden
/// and counted in a "+N more" label (docs/language.md, "Per-vehicle templates").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Flow {
    /// Down a column (wrapping to the next column on the right), else along a row
    /// (wrapping to the next row below).
    pub down: bool,
    /// The region: x, y, width, height, as a window's `rect` (px of the design, or %).
    pub rect: Vec<Bound>,
    #[serde(default)]
    pub anchor: crate::placement::Anchor,
    /// Between two instances, in design px.
    pub gap: f64,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "action")]
pub enum Action {
    /// Writes an operator goal property.
    Set {
        target: Path,
        value: Bound,
        span: Span,
    },
    /// Calls a world-model method; `target` ends with the method name.
    Call {
        target: Path,
        args: Vec<Bound>,
        span: Span,
    },
    Swap {
        a: String,
        b: String,
        duration_ms: f64,
        span: Span,
    },
    Show {
        window: String,
        span: Span,
    },
    Hide {
        window: String,
        span: Span,
    },
    Alert {
        level: String,
        message: Bound,
        span: Span,
    },
    /// Switches the binding mode (`root.operator.mode`).
    Mode {
        mode: String,
        span: Span,
    },
    /// Changes the selected object (`root.operator.selected`).
    Select {
        target: SelectTarget,
        span: Span,
    },
    /// `#js: { … }`: a script run by the engine `engine` names, on the layout's serial
    /// executor (docs/scripting.md). `span` is the body's (the text between the braces).
    Script {
        engine: String,
        body: String,
        span: Span,
        /// Where the body starts in its file: filled by [`crate::compile_layout`], which has
        /// the sources (runtime errors name it).
        #[serde(default)]
        origin: Option<ScriptOrigin>,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SelectTarget {
    /// The next (previous) child of `root.vehicles`, wrapping around.
    Next,
    Prev,
    Object(Path),
}

impl Expr {
    /// The paths and `let`s this expression names itself (not through the `let`s), each
    /// once, in order of appearance.
    pub fn reads(&self) -> Vec<Read> {
        let mut out = Vec::new();
        let mut seen_paths: Seen<&Path> = Seen::default();
        let mut seen_lets: Seen<*const Let> = Seen::default();
        self.walk(&mut |e| match &e.node {
            Node::Path(p) if seen_paths.insert(p) => out.push(Read::Path(p.clone())),
            Node::Let(l) if seen_lets.insert(Arc::as_ptr(&l.0)) => out.push(Read::Let(l.clone())),
            _ => {}
        });
        out
    }

    /// The expression a `let` use stands for (the expression itself when it is no `let`).
    pub fn peel(&self) -> &Expr {
        let mut e = self;
        while let Node::Let(l) = &e.node {
            e = &l.0.value;
        }
        e
    }

    /// The value when the expression is a constant (no paths, params or inputs), as far as
    /// simple folding goes; `None` otherwise.
    pub fn constant(&self) -> Option<Const> {
        Some(match &self.node {
            Node::Let(l) => l.0.constant?,
            Node::Number(n) | Node::Duration(n) => Const::Number(*n),
            Node::Bool(b) => Const::Bool(*b),
            Node::Unary { op: UnOp::Neg, arg } => Const::Number(-arg.constant()?.number()?),
            Node::Unary { op: UnOp::Not, arg } => Const::Bool(!arg.constant()?.bool()?),
            Node::Binary { op, lhs, rhs } => {
                let (a, b) = (lhs.constant()?, rhs.constant()?);
                match (op, a, b) {
                    (BinOp::Add, Const::Number(a), Const::Number(b)) => Const::Number(a + b),
                    (BinOp::Sub, Const::Number(a), Const::Number(b)) => Const::Number(a - b),
                    (BinOp::Mul, Const::Number(a), Const::Number(b)) => Const::Number(a * b),
                    (BinOp::Div, Const::Number(a), Const::Number(b)) => Const::Number(a / b),
                    (BinOp::Lt, Const::Number(a), Const::Number(b)) => Const::Bool(a < b),
                    (BinOp::Le, Const::Number(a), Const::Number(b)) => Const::Bool(a <= b),
                    (BinOp::Gt, Const::Number(a), Const::Number(b)) => Const::Bool(a > b),
                    (BinOp::Ge, Const::Number(a), Const::Number(b)) => Const::Bool(a >= b),
                    (BinOp::Eq, a, b) => Const::Bool(a == b),
                    (BinOp::Ne, a, b) => Const::Bool(a != b),
                    (BinOp::And, Const::Bool(a), Const::Bool(b)) => Const::Bool(a && b),
                    (BinOp::Or, Const::Bool(a), Const::Bool(b)) => Const::Bool(a || b),
                    _ => return None,
                }
            }
            Node::If { cond, then, other } => {
                if cond.constant()?.bool()? {
                    then.constant()?
                } else {
                    other.constant()?
                }
            }
            _ => return None,
        })
    }
}

/// A folded constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Const {
    Number(f64),
    Bool(bool),
}

impl Const {
    pub fn number(self) -> Option<f64> {
        if let Const::Number(n) = self { Some(n) } else { None }
    }
    pub fn bool(self) -> Option<bool> {
        if let Const::Bool(b) = self { Some(b) } else { None }
    }
}

impl Program {
    /// Calls `expr` on every expression node (pre-order) and `action` on every action.
    /// Each `let`'s value is visited once, first, however many times it is used.
    pub fn visit(&self, expr: &mut dyn FnMut(&Expr), action: &mut dyn FnMut(&Action)) {
        for l in &self.lets.0 {
            l.0.value.walk(expr);
        }
        let b = |x: &Bound, expr: &mut dyn FnMut(&Expr)| x.expr.walk(expr);
        let acts =
            |list: &[Action], expr: &mut dyn FnMut(&Expr), action: &mut dyn FnMut(&Action)| {
                for a in list {
                    action(a);
                    match a {
                        Action::Set { value, .. } => value.expr.walk(expr),
                        Action::Call { args, .. } => args.iter().for_each(|x| x.expr.walk(expr)),
                        Action::Alert { message, .. } => message.expr.walk(expr),
                        _ => {}
                    }
                }
            };
        let windows =
            self.windows.iter().chain(self.templates.iter().flat_map(|t| t.windows.iter()));
        for f in self.templates.iter().filter_map(|t| t.flow.as_ref()) {
            f.rect.iter().for_each(|x| b(x, expr));
        }
        for w in windows {
            w.rect
                .iter()
                .chain([&w.layer, &w.opacity, &w.visible])
                .chain(w.source.iter())
                .for_each(|x| b(x, expr));
        }
        let widgets =
            self.widgets.iter().chain(self.templates.iter().flat_map(|t| t.widgets.iter()));
        for w in widgets {
            w.at.iter()
                .chain(w.args.iter().map(|a| &a.value))
                .chain(w.visible.iter())
                .for_each(|x| b(x, expr));
            for h in &w.handlers {
                acts(&h.actions, expr, action);
            }
        }
        for c in &self.components {
            for s in &c.shapes {
                s.args.iter().chain(s.styles.iter().map(|a| &a.value)).for_each(|x| b(x, expr));
            }
        }
        for bnd in &self.bindings {
            acts(&bnd.actions, expr, action);
        }
        for m in &self.menus {
            for i in &m.items {
                b(&i.label, expr);
                i.enabled.iter().for_each(|x| b(x, expr));
                acts(&i.actions, expr, action);
            }
        }
        let watches =
            self.watches.iter().chain(self.templates.iter().flat_map(|t| t.watches.iter()));
        for w in watches {
            b(&w.when, expr);
            acts(&w.actions, expr, action);
        }
    }
}

impl Expr {
    /// Calls `f` on this node and every node below it. A `let` use is one node: its value
    /// is walked once, with the program's `let`s ([`Program::visit`]).
    pub fn walk<'a>(&'a self, f: &mut dyn FnMut(&'a Expr)) {
        f(self);
        match &self.node {
            Node::RangeEnd { range, .. } => range.walk(f),
            Node::Range { lo, hi } => {
                lo.walk(f);
                hi.walk(f);
            }
            Node::Unary { arg, .. } => arg.walk(f),
            Node::Binary { lhs, rhs, .. } => {
                lhs.walk(f);
                rhs.walk(f);
            }
            Node::If { cond, then, other } => {
                cond.walk(f);
                then.walk(f);
                other.walk(f);
            }
            Node::Call { args, .. } => args.iter().for_each(|a| a.walk(f)),
            Node::Format(parts) => parts.iter().for_each(|p| {
                if let FormatPart::Value { expr, .. } = p {
                    expr.walk(f)
                }
            }),
            _ => {}
        }
    }
}

mod actions;
mod lets;
mod paths;
pub use actions::ScriptOrigin;
pub use lets::*;
use paths::{Seen, collect_paths_upto};
