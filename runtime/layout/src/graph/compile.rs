//! Compiling a layout's items: functions collected by a [`Builder`] and compiled together
//! (Cranelift or the interpreter) into one [`Code`]; windows, widgets and templates before
//! they are bound to the DataServer.

use super::{LoadError, TemplateRt};
use crate::actions::{self, CompiledAction};
use crate::lower::{Base, Lowerer, Scope, Source, value_ty};
use mocu_jit::{self as jit, EvalCtx, Evaluate};
use mocu_language::placement::{self, Anchor, Edge};
use mocu_language::program::{Bound, Program, Template, Widget, Window};
use mocu_language::types::TypeKind;
use parking_lot::Mutex;
use std::sync::Arc;

/// A function before binding: its slots and output targets by name.
pub(crate) struct FuncInfo {
    pub(crate) slots: Vec<(Source, jit::Ty)>,
    /// The shared `let`s it reads ([`Source::Let`] slots), each with its function's index
    /// in the same compilation (`lets.rs`).
    pub(crate) lets: Vec<(super::lets::LetKey, usize)>,
    /// The shared `let` whose value it computes, if it is one's function.
    pub(crate) produces: Option<super::lets::LetKey>,
}

#[derive(Clone)]
pub(crate) struct CompiledWindow {
    pub(crate) name: String,
    pub(crate) kind: String,
    pub(crate) f: FnRef,
    pub(crate) source: Option<(Base, Vec<String>)>,
}

#[derive(Clone)]
pub(crate) struct CompiledWidget {
    pub(crate) name: String,
    pub(crate) window: String,
    pub(crate) component: String,
    pub(crate) native: bool,
    /// The scale components draw at (published as the widget's `scale`): the design's, but
    /// never below 1 — on a screen smaller than the design the boxes shrink and the
    /// components draw at their own size in them, so text never gets smaller than designed.
    pub(crate) scale: f64,
    pub(crate) f: FnRef,
    /// Output names, in function output order.
    pub(crate) outputs: Vec<String>,
    /// Object-typed arguments: published as dotted-path text.
    pub(crate) objects: Vec<(String, Base, Vec<String>)>,
    pub(crate) handlers: Vec<(String, Vec<CompiledAction>)>,
    /// What feeds its data parameters (their slots and the vehicle paths they read through
    /// shared `let`s): its staleness and age come from these only.
    pub(crate) data_through: Vec<(Source, jit::Ty)>,
}

fn lower_err(e: impl std::fmt::Display) -> LoadError {
    LoadError::Lower(e.to_string())
}

/// One compilation: functions compiled together into one evaluator (one code allocation).
/// Cells and actions keep their `Code` alive; code of replaced items is freed when the last
/// cell using it goes.
pub(crate) struct Code {
    pub(crate) eval: std::sync::OnceLock<Arc<dyn Evaluate>>,
    pub(crate) infos: std::sync::OnceLock<Vec<FuncInfo>>,
    pub(crate) ctx: Mutex<Option<EvalCtx>>,
}

/// A function of a compilation.
#[derive(Clone)]
pub(crate) struct FnRef {
    pub(crate) code: Arc<Code>,
    pub(crate) index: usize,
}

impl std::fmt::Debug for FnRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "fn#{}", self.index)
    }
}

impl FnRef {
    pub(crate) fn eval(&self) -> &Arc<dyn Evaluate> {
        self.code.eval.get().expect("a FnRef is used only after its Builder finished")
    }

    pub(crate) fn slots(&self) -> &[(Source, jit::Ty)] {
        &self.code.infos.get().expect("finished")[self.index].slots
    }
}

/// Collects functions while compiling a layout.
pub(crate) struct Builder {
    pub(crate) code: Arc<Code>,
    pub(crate) functions: Vec<jit::Function>,
    pub(crate) infos: Vec<FuncInfo>,
    /// The `let`s read through nodes of the graph (`lets.rs`), by number and digest.
    pub(crate) shared: Arc<std::collections::HashSet<(u32, u64)>>,
    /// The functions of the shared `let`s compiled so far.
    pub(crate) let_fns: std::collections::HashMap<super::lets::LetKey, super::lets::LetFn>,
    /// The first error met while adding a function (reported by [`Builder::finish`]).
    failed: Option<LoadError>,
    /// IR nodes of every function added ([`jit::Expr::size`]).
    pub(crate) ir_nodes: usize,
    /// Each component's data parameters (`mocu_lower::data_params`): only what feeds them
    /// makes a widget stale.
    pub(crate) data_params: Arc<std::collections::HashMap<String, Vec<String>>>,
}

impl Builder {
    pub(crate) fn new() -> Builder {
        Builder {
            code: Arc::new(Code {
                eval: std::sync::OnceLock::new(),
                infos: std::sync::OnceLock::new(),
                ctx: Mutex::new(None),
            }),
            functions: Vec::new(),
            infos: Vec::new(),
            shared: Arc::default(),
            let_fns: std::collections::HashMap::new(),
            failed: None,
            ir_nodes: 0,
            data_params: Arc::default(),
        }
    }

    /// A builder that shares the `let`s of `program` that several functions read
    /// (`lets.rs`): the functions lowered with [`Builder::lowerer`] read them through nodes.
    pub(crate) fn sharing(program: &Program) -> Builder {
        let data_params = program
            .components
            .iter()
            .map(|c| {
                (c.name.clone(), crate::lower::data_params(c).map(|p| p.name.clone()).collect())
            })
            .collect();
        Builder {
            shared: super::lets::shared_lets(program),
            data_params: Arc::new(data_params),
            ..Builder::new()
        }
    }

    /// Adds a function, and the functions of the shared `let`s it reads (an error there is
    /// reported by [`Builder::finish`]). `screen`: as `lw` was made with.
    pub(crate) fn add(&mut self, lw: Lowerer, outputs: Vec<jit::Expr>) -> FnRef {
        if !lw.shared_reads.is_empty()
            && let Err(e) = self.share(&lw, lw.screen())
        {
            self.failed.get_or_insert(e);
        }
        let index = self.push_fn(lw, outputs, None);
        FnRef { code: self.code.clone(), index }
    }

    pub(crate) fn push_fn(
        &mut self,
        lw: Lowerer,
        outputs: Vec<jit::Expr>,
        produces: Option<super::lets::LetKey>,
    ) -> usize {
        let lets = lw
            .shared_reads
            .iter()
            .filter_map(|(l, t)| {
                let key = (l.id, l.digest, *t);
                self.let_fns.get(&key).map(|f| (key, f.index))
            })
            .collect();
        let (f, slots) = lw.finish(outputs);
        self.ir_nodes += f.locals.iter().chain(&f.outputs).map(jit::Expr::size).sum::<usize>();
        self.functions.push(f);
        self.infos.push(FuncInfo { slots, lets, produces });
        self.functions.len() - 1
    }

    /// Compiles everything added (Cranelift, or the interpreter).
    pub(crate) fn finish(self, use_jit: bool) -> Result<(), LoadError> {
        if let Some(e) = self.failed {
            return Err(e);
        }
        let eval: Arc<dyn Evaluate> = if use_jit {
            Arc::new(jit::compile(&self.functions).map_err(|e| LoadError::Compile(e.to_string()))?)
        } else {
            Arc::new(
                jit::Interpreter::new(&self.functions)
                    .map_err(|e| LoadError::Compile(e.to_string()))?,
            )
        };
        *self.code.ctx.lock() = Some(eval.context());
        let _ = self.code.eval.set(eval);
        let _ = self.code.infos.set(self.infos);
        Ok(())
    }
}

/// How the program's px map to the screen: the screen's size and the design's scale
/// (`mocu_language::placement`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    pub(crate) screen: (f64, f64),
    pub(crate) scale: f64,
}

impl Frame {
    pub(crate) fn of(program: &Program, screen: (f64, f64)) -> Frame {
        Frame { screen, scale: placement::scale(program.design, screen) }
    }
}

/// A position or size in screen px: design px times the scale, or % of the screen.
fn scaled(
    lw: &mut Lowerer,
    e: &Bound,
    horizontal: bool,
    scale: f64,
) -> Result<jit::Expr, LoadError> {
    let v = lw.coordinate(&e.expr, horizontal).map_err(lower_err)?;
    if e.expr.ty.unit() == Some("%") || scale == 1.0 {
        return Ok(v);
    }
    Ok(jit::Expr::Arith(jit::Arith::Mul, Box::new(v), Box::new(jit::Expr::Num(scale))))
}

/// The `x`, `y` (and `w`, `h` when given) of a rectangle in its parent, in screen px: its
/// offsets measured from the anchor's edges (`mocu_language::placement::place`). `parent`
/// gives the parent's width (true) or height, asked only for centre and end anchors.
pub(super) fn place(
    lw: &mut Lowerer,
    rect: &[Bound],
    anchor: Anchor,
    scale: f64,
    parent: &mut dyn FnMut(&mut Lowerer, bool) -> Result<jit::Expr, LoadError>,
) -> Result<Vec<jit::Expr>, LoadError> {
    use jit::{Arith, Expr};
    let bx = Box::new;
    let mut out = Vec::new();
    for (i, edge) in [anchor.h, anchor.v].into_iter().enumerate() {
        let horizontal = i == 0;
        let Some(offset) = rect.get(i) else { break };
        let off = scaled(lw, offset, horizontal, scale)?;
        let size = || rect.get(i + 2);
        out.push(match edge {
            Edge::Start => off,
            Edge::Centre | Edge::End => {
                let p = parent(lw, horizontal)?;
                let z = match size() {
                    Some(z) => scaled(lw, z, horizontal, scale)?,
                    None => Expr::Num(0.0),
                };
                let room = Expr::Arith(Arith::Sub, bx(p), bx(z));
                if edge == Edge::Centre {
                    let half = Expr::Arith(Arith::Div, bx(room), bx(Expr::Num(2.0)));
                    Expr::Arith(Arith::Add, bx(half), bx(off))
                } else {
                    Expr::Arith(Arith::Sub, bx(room), bx(off))
                }
            }
        });
    }
    for (i, z) in rect.iter().enumerate().skip(2).take(2) {
        out.push(scaled(lw, z, i == 2, scale)?);
    }
    Ok(out)
}

pub(crate) fn compile_window(
    b: &mut Builder,
    w: &Window,
    frame: Frame,
) -> Result<CompiledWindow, LoadError> {
    let screen = frame.screen;
    let mut lw = b.lowerer(Scope::Plain, screen);
    let mut outs = vec![lw.lower(&w.layer.expr, jit::Ty::Num).map_err(lower_err)?];
    let mut parent = |_: &mut Lowerer, horizontal: bool| {
        Ok(jit::Expr::Num(if horizontal { screen.0 } else { screen.1 }))
    };
    outs.extend(place(&mut lw, &w.rect, w.anchor, frame.scale, &mut parent)?);
    while outs.len() < 5 {
        outs.push(jit::Expr::Num(0.0));
    }
    outs.push(lw.lower(&w.opacity.expr, jit::Ty::Num).map_err(lower_err)?);
    outs.push(lw.lower(&w.visible.expr, jit::Ty::Bool).map_err(lower_err)?);
    let source = match &w.source {
        Some(s) => match &s.expr.node {
            mocu_language::program::Node::Path(p) => Some(lw.path_names(p).map_err(lower_err)?),
            _ => None,
        },
        None => None,
    };
    let f = b.add(lw, outs);
    Ok(CompiledWindow { name: w.name.clone(), kind: w.kind.clone(), f, source })
}

pub(crate) const WINDOW_OUTPUTS: [&str; 7] = ["layer", "x", "y", "w", "h", "opacity", "visible"];

/// `window`: the widget's window, whose size centre and end anchors measure from (the
/// screen when it has none).
pub(crate) fn compile_widget(
    b: &mut Builder,
    w: &Widget,
    n: usize,
    frame: Frame,
    window: Option<&Window>,
) -> Result<CompiledWidget, LoadError> {
    let screen = frame.screen;
    let mut lw = b.lowerer(Scope::Widget { args: &w.args, at: &w.at }, screen);
    let mut outs = Vec::new();
    let mut names = Vec::new();
    let mut parent = |lw: &mut Lowerer, horizontal: bool| {
        let i = if horizontal { 2 } else { 3 };
        match window.and_then(|win| win.rect.get(i)) {
            Some(size) => scaled(lw, size, horizontal, frame.scale),
            None => Ok(jit::Expr::Num(if horizontal { screen.0 } else { screen.1 })),
        }
    };
    let at = &w.at[..w.at.len().min(4)];
    outs.extend(place(&mut lw, at, w.anchor, frame.scale, &mut parent)?);
    names.extend(["x", "y", "w", "h"][..at.len()].iter().map(|n| n.to_string()));
    if let Some(v) = &w.visible {
        outs.push(lw.lower(&v.expr, jit::Ty::Bool).map_err(lower_err)?);
        names.push("visible".into());
    }
    let mut objects = Vec::new();
    for a in &w.args {
        let e = &a.value.expr;
        match &e.ty.kind {
            TypeKind::Range { .. } => {
                for (end, max) in [("min", false), ("max", true)] {
                    let re = mocu_language::program::Expr {
                        ty: mocu_language::types::Type::number(),
                        node: mocu_language::program::Node::RangeEnd {
                            range: Box::new(e.clone()),
                            max,
                        },
                        span: e.span,
                    };
                    outs.push(lw.lower(&re, jit::Ty::Num).map_err(lower_err)?);
                    names.push(format!("{}.{end}", a.name));
                }
            }
            // An object, or a path typed only at run time given to a native widget's
            // object parameter (`Map { follow usv }` without a schema); through `let`s too.
            TypeKind::Object { .. } | TypeKind::Dynamic
                if matches!(e.ty.kind, TypeKind::Object { .. })
                    || mocu_language::builtins::native(&w.component).is_some_and(|n| {
                        n.params.iter().any(|(p, t, _)| *p == a.name && *t == "object")
                    }) =>
            {
                if let mocu_language::program::Node::Path(p) = &e.peel().node {
                    let (base, objs) = lw.path_names(p).map_err(lower_err)?;
                    objects.push((a.name.clone(), base, objs));
                }
            }
            TypeKind::Void | TypeKind::Error => {}
            _ => {
                let ty = value_ty(&e.ty).unwrap_or(jit::Ty::Num);
                outs.push(lw.lower(e, ty).map_err(lower_err)?);
                names.push(a.name.clone());
            }
        }
    }
    let through = b.share(&lw, screen)?;
    // Only the vehicles feeding the data parameters make the widget stale (a button that
    // is enabled while a vehicle is armed, an alert that is active while its fuel is low, a
    // dial placed by a vehicle's property are not veiled by that vehicle's age).
    let through = match b.data_params.clone().get(&w.component) {
        Some(data) => {
            let mut dl = b.lowerer(Scope::Widget { args: &w.args, at: &w.at }, screen);
            for a in w.args.iter().filter(|a| data.contains(&a.name)) {
                let ty = value_ty(&a.value.expr.ty).unwrap_or(jit::Ty::Num);
                dl.lower(&a.value.expr, ty).map_err(lower_err)?;
            }
            b.share(&dl, screen)?
        }
        None => through, // a native widget: all it reads
    };
    let data_through = through.clone();
    if let Some(stale) = crate::stale::widget_stale(&mut lw, &through) {
        outs.push(stale);
        names.push("stale".into());
    }
    let f = b.add(lw, outs);
    let mut handlers = Vec::new();
    for h in &w.handlers {
        let acts = actions::compile_actions(b, &h.actions, screen).map_err(lower_err)?;
        handlers.push((h.event.clone(), acts));
    }
    let name = w.name.clone().unwrap_or_else(|| format!("{}#{n}", w.component));
    Ok(CompiledWidget {
        name,
        window: w.window.clone(),
        component: w.component.clone(),
        native: w.native,
        scale: frame.scale.max(1.0),
        f,
        outputs: names,
        objects,
        handlers,
        data_through,
    })
}

/// `program_windows`: the top-level windows, which a template's widgets may be in too.
pub(crate) fn compile_template(
    b: &mut Builder,
    t: &Template,
    frame: Frame,
    program_windows: &[Window],
) -> Result<TemplateRt, LoadError> {
    let screen = frame.screen;
    let windows =
        t.windows.iter().map(|w| compile_window(b, w, frame)).collect::<Result<_, _>>()?;
    let window_of = |name: &str| t.windows.iter().chain(program_windows).find(|w| w.name == name);
    let widgets = t
        .widgets
        .iter()
        .enumerate()
        .map(|(i, w)| compile_widget(b, w, i, frame, window_of(&w.window)))
        .collect::<Result<_, _>>()?;
    let watches = t
        .watches
        .iter()
        .map(|w| crate::watch::compile_watch(b, w, screen))
        .collect::<Result<_, _>>()?;
    if t.source.base != mocu_language::program::PathBase::Root {
        return Err(LoadError::Lower(format!(
            "`for each` over `{}`: the source must start at root",
            t.source
        )));
    }
    let flow = match (&t.flow, t.windows.first()) {
        (Some(f), Some(first)) => Some(super::flow::compile_flow(b, f, frame, &first.name)?),
        _ => None,
    };
    Ok(TemplateRt {
        alive: true,
        source: t.source.segments.clone(),
        object_type: t.object_type.clone(),
        var: t.var.clone(),
        flow,
        windows,
        widgets,
        watches,
        source_watch: None,
        source_object: None,
        children_sub: None,
    })
}
