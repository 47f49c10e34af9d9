//! Pass 5b: method arguments against the schema's parameter types (E0302). What the
//! DataServer would refuse at run time ("argument `on` of `arm` must be bool, got string") is
//! refused here first: a `bool` parameter takes a condition, `int` a whole number (a constant
//! like `1.5` is refused), `float` a number, `string` a string, `guid` an object path (the
//! runtime passes the object's GUID). Paths whose type only the world knows (`dynamic`) are
//! accepted. Without a schema nothing is reported. Runs after `check_schema` (argument counts).

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;
use crate::schema::{Lookup, Method, Schema};
use crate::types::{Type, TypeKind};
use mocu_value::ValueKind;

pub fn check_method_args(program: &Program, schema: &Schema, diags: &mut Diagnostics) {
    if schema.is_empty() {
        return;
    }
    program.visit(&mut |_| {}, &mut |a| {
        if let Action::Call { target, args, .. } = a {
            let l = schema.lookup(
                target.base_type.as_deref(),
                target.base == PathBase::Root,
                &target.segments,
            );
            if let Lookup::Method(m) = l {
                check_call(target, m, args, diags);
            }
        }
    });
}

fn check_call(target: &Path, m: &Method, args: &[Bound], diags: &mut Diagnostics) {
    let signature = format!(
        "{}({})",
        target.segments.last().map_or("", String::as_str),
        m.params.iter().map(|k| k.to_string()).collect::<Vec<_>>().join(", ")
    );
    for (i, (kind, arg)) in m.params.iter().zip(args).enumerate() {
        let e = &arg.expr;
        if e.ty.is_lenient() {
            continue;
        }
        let fits = match kind {
            ValueKind::Bool => matches!(e.ty.kind, TypeKind::Bool),
            ValueKind::Int | ValueKind::Float => matches!(e.ty.kind, TypeKind::Number { .. }),
            ValueKind::String => matches!(e.ty.kind, TypeKind::String),
            ValueKind::Guid => matches!(e.ty.kind, TypeKind::Object { .. }),
            _ => true,
        };
        if !fits {
            diags
                .error(
                    codes::TYPE_MISMATCH,
                    e.span,
                    format!(
                        "argument {} of `{target}` must be {}, but this is {}",
                        i + 1,
                        kind_text(*kind),
                        type_text(&e.ty)
                    ),
                )
                .label(format!("this is {}", type_text(&e.ty)))
                .help(format!("the schema declares `{signature}`"));
            continue;
        }
        if *kind == ValueKind::Int
            && let Some(n) = e.constant().and_then(|c| c.number())
            && (n.fract() != 0.0 || !n.is_finite())
        {
            diags
                .error(
                    codes::TYPE_MISMATCH,
                    e.span,
                    format!("argument {} of `{target}` must be a whole number, not {n}", i + 1),
                )
                .label("not a whole number")
                .help(format!("the schema declares `{signature}`"));
        }
    }
}

fn kind_text(k: ValueKind) -> &'static str {
    match k {
        ValueKind::Bool => "a bool (`true`, `false` or a condition)",
        ValueKind::Int => "a whole number",
        ValueKind::Float => "a number",
        ValueKind::String => "a string",
        ValueKind::Guid => "an object (a path such as `usv.routes.survey`)",
        _ => "a value of another kind",
    }
}

fn type_text(t: &Type) -> String {
    match &t.kind {
        TypeKind::Number { unit: Some(u) } => format!("a number ({u})"),
        TypeKind::Number { unit: None } => "a number".into(),
        TypeKind::Bool => "a bool".into(),
        TypeKind::String => "a string".into(),
        TypeKind::Colour => "a colour".into(),
        TypeKind::Duration => "a duration".into(),
        TypeKind::Range { .. } => "a range".into(),
        TypeKind::Object { .. } => "an object".into(),
        _ => t.to_string(),
    }
}
