//! Compiling a layout's items: functions collected by a [`Builder`] and compiled together
//! (Cranelift or the interpreter) into one [`Code`]; windows, widgets and templates before
//! they are bound to the DataServer.

use super::{LoadError, TemplateRt};
use crate::actions::{self, CompiledAction};
use crate::lower::{Base, Lowerer, Scope, Source, value_ty};
use mocu_jit::{self as jit, EvalCtx, Evaluate};
use mocu_language::program::{Template, Widget, Window};
use mocu_language::types::TypeKind;
use parking_lot::Mutex;
use std::sync::Arc;

/// A function before binding: its slots and output targets by name.
pub(crate) struct FuncInfo {
    pub(crate) slots: Vec<(Source, jit::Ty)>,
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
    pub(crate) f: FnRef,
    /// Output names, in function output order.
    pub(crate) outputs: Vec<String>,
    /// Object-typed arguments: published as dotted-path text.
    pub(crate) objects: Vec<(String, Base, Vec<String>)>,
    pub(crate) handlers: Vec<(String, Vec<CompiledAction>)>,
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
        }
    }

    pub(crate) fn add(&mut self, lw: Lowerer, outputs: Vec<jit::Expr>) -> FnRef {
        let inputs = lw.slots.iter().map(|s| s.1).collect();
        self.functions.push(jit::Function { inputs, outputs });
        self.infos.push(FuncInfo { slots: lw.slots });
        FnRef { code: self.code.clone(), index: self.functions.len() - 1 }
    }

    /// Compiles everything added (Cranelift, or the interpreter).
    pub(crate) fn finish(self, use_jit: bool) -> Result<(), LoadError> {
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

pub(crate) fn compile_window(
    b: &mut Builder,
    w: &Window,
    screen: (f64, f64),
) -> Result<CompiledWindow, LoadError> {
    let mut lw = Lowerer::new(Scope::Plain, screen);
    let mut outs = vec![lw.lower(&w.layer.expr, jit::Ty::Num).map_err(lower_err)?];
    for (i, r) in w.rect.iter().enumerate().take(4) {
        outs.push(lw.coordinate(&r.expr, i % 2 == 0).map_err(lower_err)?);
    }
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

pub(crate) fn compile_widget(
    b: &mut Builder,
    w: &Widget,
    n: usize,
    screen: (f64, f64),
) -> Result<CompiledWidget, LoadError> {
    let mut lw = Lowerer::new(Scope::Widget { args: &w.args, at: &w.at }, screen);
    let mut outs = Vec::new();
    let mut names = Vec::new();
    for (i, a) in w.at.iter().enumerate().take(4) {
        outs.push(lw.coordinate(&a.expr, i % 2 == 0).map_err(lower_err)?);
        names.push(["x", "y", "w", "h"][i].to_string());
    }
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
            TypeKind::Object { .. } => {
                if let mocu_language::program::Node::Path(p) = &e.node {
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
    if let Some(stale) = crate::stale::widget_stale(&mut lw) {
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
        f,
        outputs: names,
        objects,
        handlers,
    })
}

pub(crate) fn compile_template(
    b: &mut Builder,
    t: &Template,
    screen: (f64, f64),
) -> Result<TemplateRt, LoadError> {
    let windows =
        t.windows.iter().map(|w| compile_window(b, w, screen)).collect::<Result<_, _>>()?;
    let widgets = t
        .widgets
        .iter()
        .enumerate()
        .map(|(i, w)| compile_widget(b, w, i, screen))
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
    Ok(TemplateRt {
        alive: true,
        source: t.source.segments.clone(),
        object_type: t.object_type.clone(),
        var: t.var.clone(),
        windows,
        widgets,
        watches,
        source_watch: None,
        source_object: None,
        children_sub: None,
    })
}
