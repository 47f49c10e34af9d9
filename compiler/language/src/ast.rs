//! The syntax tree: what the parser produces, before any check. Every node has a [`Span`].

use crate::source::Span;

#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

/// One parsed file: its items (broken items are left out and reported).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct File {
    pub items: Vec<Item>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    Use(Use),
    Let(Let),
    Window(Window),
    In(InBlock),
    Component(Component),
    Bind(Bind),
    Menu(Menu),
    /// Boxed, as `Each`: the largest items, and the rarest, so that every item is not their size.
    Watch(Box<Watch>),
    Each(Box<Each>),
    Design(Design),
}

/// `design 1280 x 720`: the screen size the layout's px are written for.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    pub width: Expr,
    pub height: Expr,
    pub span: Span,
}

/// `use "path.mocu"` or `use "path.mocu" as ns`.
#[derive(Clone, Debug, PartialEq)]
pub struct Use {
    pub path: String,
    pub path_span: Span,
    pub alias: Option<Ident>,
    pub span: Span,
}

/// `let name = expr`.
#[derive(Clone, Debug, PartialEq)]
pub struct Let {
    pub name: Ident,
    pub value: Expr,
    pub span: Span,
}

/// `window name { rect … layer … }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Window {
    pub name: Ident,
    pub rect: Option<Vec<Expr>>,
    /// `anchor bottom-right` (checked in passes/check_anchors.rs).
    pub anchor: Option<Ident>,
    pub props: Vec<Prop>,
    pub span: Span,
}

/// `name expr` inside a window, widget or primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Prop {
    pub name: Ident,
    pub value: Expr,
    pub span: Span,
}

/// `in window { widget… }`.
#[derive(Clone, Debug, PartialEq)]
pub struct InBlock {
    pub window: Ident,
    pub widgets: Vec<Widget>,
    pub span: Span,
}

/// `name: Component { at x y w h  param expr …  on event action… }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Widget {
    pub name: Option<Ident>,
    pub component: Ident,
    pub at: Option<(Vec<Expr>, Span)>,
    pub anchor: Option<Ident>,
    pub args: Vec<Prop>,
    pub handlers: Vec<Handler>,
    pub span: Span,
}

/// `on event action…`.
#[derive(Clone, Debug, PartialEq)]
pub struct Handler {
    pub event: Ident,
    pub actions: Vec<Action>,
    pub span: Span,
}

/// `component Name(params) { let…  primitive… }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Component {
    pub name: Ident,
    pub params: Vec<Param>,
    pub body: Vec<Stmt>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    Value { name: Ident, ty: Option<TypeName>, default: Option<Expr> },
    Event { name: Ident },
}

impl Param {
    pub fn name(&self) -> &Ident {
        match self {
            Param::Value { name, .. } | Param::Event { name } => name,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct TypeName {
    pub name: Ident,
    pub optional: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Stmt {
    Let(Let),
    Primitive(Primitive),
}

/// `circle cx cy r  fill c  stroke c …`.
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    pub kind: Ident,
    pub args: Vec<Expr>,
    pub styles: Vec<Prop>,
    pub span: Span,
}

/// `bind gamepad { shift left_bumper  axis left_y … -> action…  mode drive { … } }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Bind {
    pub device: Ident,
    /// `shift NAME`: the input that selects the shift layer.
    pub shift: Option<Ident>,
    /// Bindings active in every mode.
    pub bindings: Vec<Binding>,
    /// `mode NAME { binding… }`: bindings active only in that mode.
    pub modes: Vec<(Ident, Vec<Binding>)>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Binding {
    /// Written `shift button west -> …`: active only while the shift input is held.
    pub shift: bool,
    pub kind: Ident,
    pub input: Ident,
    /// `deadzone 0.1`, `invert`, `hold 500ms`, `double`, … in order.
    pub options: Vec<BindingOption>,
    pub actions: Vec<Action>,
    pub span: Span,
}

/// One option after a binding's input name: a keyword and maybe a number.
#[derive(Clone, Debug, PartialEq)]
pub struct BindingOption {
    pub name: Ident,
    pub value: Option<Expr>,
    pub span: Span,
}

/// `menu for type "usv" { item "Arm" enabled expr -> action… }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Menu {
    pub object_type: String,
    pub type_span: Span,
    pub entries: Vec<MenuEntry>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct MenuEntry {
    pub label: Expr,
    pub enabled: Option<Expr>,
    pub actions: Vec<Action>,
    pub span: Span,
}

/// `watch name { when cond for 5s clear when cond2 repeat every 30s then action… }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Watch {
    pub name: Ident,
    pub when: Expr,
    pub hold: Option<Expr>,
    /// Hysteresis: once fired, the watch stays active until this holds.
    pub clear: Option<Expr>,
    /// Level triggering: while active, the actions run again every period.
    pub repeat: Option<Expr>,
    pub actions: Vec<Action>,
    pub span: Span,
}

/// `for each v in root.vehicles of type "usv" { window… in… watch… }`: a per-object template.
#[derive(Clone, Debug, PartialEq)]
pub struct Each {
    pub var: Ident,
    pub source: Expr,
    pub object_type: Option<(String, Span)>,
    /// `flow down rect … anchor … gap …`: the runtime places the instances' windows.
    pub flow: Option<Flow>,
    pub items: Vec<Item>,
    pub span: Span,
}

/// `flow DIRECTION rect X Y W H [anchor NAME] [gap N]` in a `for each` header: the region
/// the instances' windows are placed in, one after another (checked in check_types).
#[derive(Clone, Debug, PartialEq)]
pub struct Flow {
    /// `down` or `right` (E0215 for others).
    pub direction: Ident,
    pub rect: Vec<Expr>,
    pub anchor: Option<Ident>,
    pub gap: Option<Expr>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Action {
    pub kind: ActionKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ActionKind {
    Set {
        target: Expr,
        value: Expr,
    },
    Call {
        call: Expr,
    },
    Swap {
        a: Ident,
        b: Ident,
        duration: Option<Expr>,
    },
    Show {
        window: Ident,
    },
    Hide {
        window: Ident,
    },
    Alert {
        level: Ident,
        message: Expr,
    },
    /// `mode payload`: switch the binding mode.
    Mode {
        mode: Ident,
    },
    /// `select next`, `select prev`, `select path`: change the selected object.
    Select {
        target: SelectTarget,
    },
    /// `#js: { … }`: a script for the engine `engine` names (`js`, its span the prefix's);
    /// `body` is the text between the braces, `body_span` where it is.
    Script {
        engine: Ident,
        body: String,
        body_span: Span,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub enum SelectTarget {
    Next,
    Prev,
    Object(Expr),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BinOp {
    Coalesce,
    Range,
    Or,
    And,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
    Add,
    Sub,
    Mul,
    Div,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnOp {
    Neg,
    Not,
}

/// A suffix written after a number literal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LitUnit {
    Ms,
    S,
    Min,
    Px,
    Deg,
    Percent,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    Number {
        value: f64,
        unit: Option<LitUnit>,
    },
    Str(Vec<StrPart>),
    Colour(u32),
    Bool(bool),
    Name(String),
    SelfRef,
    Field(Box<Expr>, Ident),
    Index(Box<Expr>, String),
    Call(Box<Expr>, Vec<Expr>),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    If(Box<Expr>, Box<Expr>, Box<Expr>),
    /// An expression that did not parse (already reported): typed as an error, silently,
    /// so that a broken `let` still defines its name without follow-on errors.
    Error,
}

#[derive(Clone, Debug, PartialEq)]
pub enum StrPart {
    Text(String),
    Interp { expr: Expr, spec: Option<(String, Span)> },
}

impl BinOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Coalesce => "??",
            BinOp::Range => "..",
            BinOp::Or => "||",
            BinOp::And => "&&",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
        }
    }
}
