//! Pass 5: the program against the schema. Reports calls of what is not a method (E0401;
//! unknown members are reported by `check_types`, where each segment's span is known), constants outside a declared range in `set` and in
//! comparisons (E0403), `set` of a read-only property (E0404), and method argument counts
//! (E0303). Without a schema nothing is reported: paths are discovered at run time.
//! Runs after `check_types`, on the typed program, where every path is complete.

use crate::ast::BinOp;
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;
use crate::schema::{Lookup, Property, Schema};
use crate::source::Span;

pub fn check_schema(program: &Program, schema: &Schema, diags: &mut Diagnostics) {
    if schema.is_empty() {
        return;
    }
    let c = std::cell::RefCell::new(Checker { schema, diags });
    program.visit(&mut |e| c.borrow_mut().expr(e), &mut |a| c.borrow_mut().action(a));
}

struct Checker<'a, 'd> {
    schema: &'a Schema,
    diags: &'d mut Diagnostics,
}

impl Checker<'_, '_> {
    fn lookup<'s>(&'s mut self, p: &'s Path, span: Span) -> Option<Lookup<'s>> {
        let from_root = p.base == PathBase::Root;
        let l = self.schema.lookup(p.base_type.as_deref(), from_root, &p.segments);
        if let Lookup::Unknown { object_type, index, candidates } = &l {
            let name = &p.segments[*index];
            // `check_types` reported it at the segment already (`call usv.upload_rout()`):
            // one mistake, one diagnostic.
            let inside = |d: &crate::diagnostics::Diagnostic| {
                d.code == codes::UNKNOWN_PROPERTY
                    && d.span.file == span.file
                    && span.start <= d.span.start
                    && d.span.end <= span.end
            };
            if self.diags.iter().any(inside) {
                return None;
            }
            self.diags
                .error(
                    codes::UNKNOWN_PROPERTY,
                    span,
                    format!("an object of type \"{object_type}\" has no property `{name}`"),
                )
                .label(format!("`{name}` is not in the schema"))
                .suggest(name, candidates.iter().copied());
            return None;
        }
        Some(l)
    }

    fn property<'s>(&'s self, p: &Path) -> Option<&'s Property> {
        match self.schema.lookup(p.base_type.as_deref(), p.base == PathBase::Root, &p.segments) {
            Lookup::Property(prop) => Some(prop),
            _ => None,
        }
    }

    fn expr(&mut self, e: &Expr) {
        if let Node::Binary {
            op: BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne,
            lhs,
            rhs,
        } = &e.node
        {
            for (path, other) in [(lhs, rhs), (rhs, lhs)] {
                if let (Node::Path(p), Some(c)) =
                    (&path.node, other.constant().and_then(|c| c.number()))
                    && let Some(prop) = self.property(p).cloned()
                {
                    self.range(&prop, c, other.span, p);
                }
            }
        }
    }

    fn range(&mut self, prop: &Property, value: f64, span: Span, p: &Path) {
        if let Some([lo, hi]) = prop.range
            && (value < lo || value > hi)
        {
            self.diags
                .error(
                    codes::OUT_OF_RANGE,
                    span,
                    format!("{value} is outside the range of `{p}`, {lo} ..= {hi}"),
                )
                .label("out of range")
                .help(format!(
                    "the schema declares {lo} ..= {hi}{}",
                    prop.units.as_deref().map(|u| format!(" {u}")).unwrap_or_default()
                ));
        }
    }

    fn action(&mut self, a: &Action) {
        match a {
            Action::Set { target, value, span } => {
                if let Some(Lookup::Property(prop)) = self.lookup(target, *span) {
                    let prop = prop.clone();
                    if prop.read_only {
                        self.diags
                            .error(codes::READ_ONLY, *span, format!("`{target}` is read-only"))
                            .help("the schema marks it read_only: it is measured, not commanded; set its goal property instead");
                    }
                    if let Some(c) = value.expr.constant().and_then(|c| c.number()) {
                        self.range(&prop, c, value.expr.span, target);
                    }
                }
            }
            Action::Call { target, args, span } => match self.lookup(target, *span) {
                Some(Lookup::Method(m)) => {
                    let want = m.params.len();
                    if want != args.len() {
                        self.diags.error(
                            codes::ARG_COUNT,
                            *span,
                            format!(
                                "`{target}` takes {want} argument(s), but {} were given",
                                args.len()
                            ),
                        );
                    }
                }
                Some(Lookup::Property(_) | Lookup::Object(_)) => {
                    self.diags.error(
                        codes::UNKNOWN_PROPERTY,
                        *span,
                        format!("`{target}` is not a method"),
                    );
                }
                _ => {}
            },
            _ => {}
        }
    }
}
