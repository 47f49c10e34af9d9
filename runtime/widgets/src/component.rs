//! Components compiled once each: every shape argument and style of a component body is an
//! output of one function whose inputs are the widget's parameters and size.

use mocu_jit::{self as jit, Evaluate, Slot};
use mocu_language::program::{Component, Program};
use mocu_lower::convert::{to_slot, to_value};
use mocu_lower::{LowerError, Lowerer, Scope, Source, value_ty};
use mocu_value::Value;
use std::collections::HashMap;
use std::sync::Arc;

/// One primitive of a component body, as laid out in the function's outputs.
#[derive(Clone, Debug)]
pub struct ShapeOut {
    pub kind: String,
    /// Outputs `first .. first + args` are the positional arguments.
    pub first: usize,
    pub args: usize,
    /// Style name → output index.
    pub styles: Vec<(String, usize)>,
}

/// A compiled component.
pub struct Compiled {
    pub name: String,
    pub func: usize,
    /// Where each input slot comes from: a parameter (`value`, `range.min`) or `w`/`h`.
    pub slots: Vec<(String, jit::Ty)>,
    pub shapes: Vec<ShapeOut>,
    pub events: Vec<String>,
    /// The data parameters (`value: number?`, `text: string`, a toggle's `state: bool?`;
    /// `mocu_lower::data_params`): a widget that was given one of them is veiled when its
    /// `stale` or `aged` property says the data feeding them is old.
    pub data: Vec<String>,
}

/// Every component of a program, compiled together.
pub struct Library {
    pub eval: Arc<dyn Evaluate>,
    pub components: HashMap<String, Compiled>,
}

impl Library {
    pub fn compile(program: &Program, use_jit: bool) -> Result<Library, String> {
        let mut functions = Vec::new();
        let mut components = HashMap::new();
        for c in &program.components {
            let (f, compiled) = compile_component(c, functions.len())
                .map_err(|e| format!("component `{}`: {e}", c.name))?;
            functions.push(f);
            components.insert(c.name.clone(), compiled);
        }
        let eval: Arc<dyn Evaluate> = if use_jit {
            Arc::new(jit::compile(&functions).map_err(|e| e.to_string())?)
        } else {
            Arc::new(jit::Interpreter::new(&functions).map_err(|e| e.to_string())?)
        };
        Ok(Library { eval, components })
    }

    /// Evaluates a component for a widget: `prop` reads the widget's properties.
    pub fn evaluate(
        &self,
        c: &Compiled,
        prop: &dyn Fn(&str) -> Option<Value>,
    ) -> Vec<Option<Value>> {
        let mut ctx = self.eval.context();
        let slots: Vec<Slot> =
            c.slots.iter().map(|(name, ty)| to_slot(prop(name).as_ref(), *ty, &mut ctx)).collect();
        let types = self.eval.output_types(c.func);
        let mut outs = vec![Slot::ABSENT; types.len()];
        self.eval.call(c.func, &slots, &mut outs, &mut ctx);
        outs.iter().zip(types).map(|(s, t)| to_value(s.decode(*t, &ctx))).collect()
    }
}

/// The type a style has (the checker knows it; lowering needs it for dynamic values).
fn style_ty(name: &str) -> jit::Ty {
    match name {
        "fill" | "stroke" | "colour" => jit::Ty::Color,
        "align" | "font" => jit::Ty::Str,
        "visible" => jit::Ty::Bool,
        _ => jit::Ty::Num,
    }
}

fn compile_component(c: &Component, index: usize) -> Result<(jit::Function, Compiled), LowerError> {
    let mut lw = Lowerer::new(Scope::Component, (1.0, 1.0));
    let mut outs = Vec::new();
    let mut shapes = Vec::new();
    for s in &c.shapes {
        let first = outs.len();
        for (i, a) in s.args.iter().enumerate() {
            // The text of `text` and the source of `image` are strings; the rest numbers.
            let text_arg = (s.kind == "text" && i == 2) || (s.kind == "image" && i == 4);
            let want = if text_arg { jit::Ty::Str } else { jit::Ty::Num };
            let ty = value_ty(&a.expr.ty).unwrap_or(want);
            // A number shown by `text` is written with its default format.
            let e = if want == jit::Ty::Str && ty == jit::Ty::Num {
                jit::Expr::Format(vec![jit::Piece::Num(
                    lw.lower(&a.expr, ty)?,
                    jit::NumFormat::default(),
                )])
            } else {
                lw.lower(&a.expr, ty)?
            };
            outs.push(e);
        }
        let mut styles = Vec::new();
        for st in &s.styles {
            let ty = value_ty(&st.value.expr.ty).unwrap_or(style_ty(&st.name));
            styles.push((st.name.clone(), outs.len()));
            outs.push(lw.lower(&st.value.expr, ty)?);
        }
        shapes.push(ShapeOut { kind: s.kind.clone(), first, args: s.args.len(), styles });
    }
    let (function, sources) = lw.finish(outs);
    let slots: Vec<(String, jit::Ty)> = sources
        .iter()
        .map(|(src, ty)| match src {
            Source::Param(n) => (n.clone(), *ty),
            other => (format!("{other:?}"), *ty),
        })
        .collect();
    Ok((
        function,
        Compiled {
            name: c.name.clone(),
            func: index,
            slots,
            shapes,
            events: c.events.clone(),
            data: mocu_lower::data_params(c).map(|p| p.name.clone()).collect(),
        },
    ))
}
