//! Expressions: lowering the syntax tree to typed program nodes, paths typed from the schema,
//! built-in calls, interpolated strings, operators and their units.

use super::*;

impl<'a> Typer<'a, '_> {
    pub(super) fn lower(&mut self, e: &ast::Expr, scope: &Scope<'a>) -> Expr {
        // Nesting up to the depth limit takes ~9 KiB of stack a level in a debug build: more
        // than a 2 MiB thread has. Grow the stack when less than 64 KiB is left.
        stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.lower_node(e, scope))
    }

    pub(super) fn lower_node(&mut self, e: &ast::Expr, scope: &Scope<'a>) -> Expr {
        let span = e.span;
        match &e.kind {
            ExprKind::Number { value, unit } => match unit {
                Some(LitUnit::Ms) => mk(Type::DURATION, Node::Duration(*value), span),
                Some(LitUnit::S) => mk(Type::DURATION, Node::Duration(value * 1000.0), span),
                Some(LitUnit::Min) => mk(Type::DURATION, Node::Duration(value * 60_000.0), span),
                Some(LitUnit::Px) => {
                    mk(Type::number_in(Some(literal_unit("px"))), Node::Number(*value), span)
                }
                Some(LitUnit::Deg) => {
                    mk(Type::number_in(Some(literal_unit("deg"))), Node::Number(*value), span)
                }
                Some(LitUnit::Percent) => {
                    mk(Type::number_in(Some(literal_unit("%"))), Node::Number(*value), span)
                }
                None => mk(Type::number(), Node::Number(*value), span),
            },
            ExprKind::Bool(b) => mk(Type::BOOL, Node::Bool(*b), span),
            ExprKind::Error => mk(Type::ERROR, Node::Bool(false), span),
            ExprKind::Colour(c) => mk(Type::COLOUR, Node::Colour(*c), span),
            ExprKind::Str(parts) => self.string(parts, scope, span),
            ExprKind::SelfRef => match &scope.self_type {
                Some(t) => mk(
                    Type {
                        kind: TypeKind::Object { object_type: t.as_deref().map(Name::new) },
                        absent: true,
                    },
                    Node::Path(Path {
                        base: PathBase::SelfObject,
                        segments: vec![],
                        base_type: t.clone(),
                    }),
                    span,
                ),
                None => mk(Type::ERROR, Node::Bool(false), span),
            },
            ExprKind::Name(n) => {
                if let Some((_, local)) = scope.locals.iter().rev().find(|(name, _)| name == n) {
                    return Expr { span, ..local.clone() };
                }
                if let Some(id) = self.defs.find_let(self.modules, scope.module, n, scope.limit)
                    && let Some(v) = self.top_let(id, span)
                {
                    return v;
                }
                if n == "selected" {
                    return mk(
                        Type { kind: TypeKind::Object { object_type: None }, absent: true },
                        Node::Path(Path {
                            base: PathBase::Selected,
                            segments: vec![],
                            base_type: None,
                        }),
                        span,
                    );
                }
                if n == "root" {
                    return mk(
                        Type::new(TypeKind::Object { object_type: None }),
                        Node::Path(Path {
                            base: PathBase::Root,
                            segments: vec![],
                            base_type: None,
                        }),
                        span,
                    );
                }
                mk(Type::ERROR, Node::Bool(false), span)
            }
            ExprKind::Field(base, field) => {
                if let ExprKind::Name(ns) = &base.kind {
                    let shadowed = scope.locals.iter().any(|(n, _)| n == ns)
                        || self
                            .defs
                            .find_let(self.modules, scope.module, ns, scope.limit)
                            .is_some();
                    if let (false, Some(target)) =
                        (shadowed, self.defs.namespace(self.modules, scope.module, ns))
                    {
                        let id = self.defs.lets[target].get(&field.name).copied();
                        return match id.and_then(|id| self.top_let(id, span)) {
                            Some(v) => v,
                            None => mk(Type::ERROR, Node::Bool(false), span),
                        };
                    }
                }
                let b = self.lower(base, scope);
                self.member(b, field.name.clone(), span, field.span)
            }
            ExprKind::Index(base, key) => {
                let b = self.lower(base, scope);
                self.member(b, key.clone(), span, span)
            }
            ExprKind::Call(callee, args) => {
                let ExprKind::Name(f) = &callee.kind else {
                    let c = self.lower(callee, scope);
                    if c.ty.kind != TypeKind::Error {
                        self.diags
                            .error(codes::MISPLACED_CALL, span, "a method call can only be an action")
                            .help("methods act on the world: use them as `call obj.method(…)` in a button, binding, menu or watch");
                    }
                    return mk(Type::ERROR, Node::Bool(false), span);
                };
                let args: Vec<Expr> = args.iter().map(|a| self.lower(a, scope)).collect();
                self.builtin_call(f, args, span, callee.span)
            }
            ExprKind::Unary(op, a) => {
                let a = self.lower(a, scope);
                let ty = match op {
                    UnOp::Neg => {
                        if matches!(a.ty.kind, TypeKind::Duration) {
                            a.ty
                        } else {
                            if !a.ty.is_numeric() {
                                self.not_a_number(&a, &"an operand");
                            }
                            if a.ty.is_numeric() {
                                Type::number_in(unit_of(&a.ty)).maybe_absent(a.ty.absent)
                            } else {
                                Type::ERROR
                            }
                        }
                    }
                    UnOp::Not => {
                        if !a.ty.is_bool() {
                            self.diags
                                .error(
                                    codes::NOT_BOOL,
                                    a.span,
                                    format!("`!` needs a condition (bool), but this is a {}", a.ty),
                                )
                                .label(format!("this is a {}", a.ty));
                        }
                        Type::BOOL.maybe_absent(a.ty.absent)
                    }
                };
                mk(ty, Node::Unary { op: *op, arg: Box::new(a) }, span)
            }
            ExprKind::Binary(op, a, b) => {
                let a = self.lower(a, scope);
                let b = self.lower(b, scope);
                let ty = self.binary_type(*op, &a, &b);
                if *op == BinOp::Range {
                    return mk(ty, Node::Range { lo: Box::new(a), hi: Box::new(b) }, span);
                }
                mk(ty, Node::Binary { op: *op, lhs: Box::new(a), rhs: Box::new(b) }, span)
            }
            ExprKind::If(c, a, b) => {
                let c = self.lower(c, scope);
                if !c.ty.is_bool() {
                    self.diags
                        .error(
                            codes::NOT_BOOL,
                            c.span,
                            format!("the condition of `if` must be a bool, but this is a {}", c.ty),
                        )
                        .label(format!("this is a {}", c.ty));
                }
                let a = self.lower(a, scope);
                let b = self.lower(b, scope);
                let ty = if a.ty.is_lenient() {
                    b.ty.maybe_absent(a.ty.absent)
                } else if b.ty.is_lenient() || a.ty.fits(&b.ty) {
                    a.ty.maybe_absent(b.ty.absent)
                } else {
                    self.diags
                        .error(
                            codes::TYPE_MISMATCH,
                            b.span,
                            format!("the branches of `if` differ: {} and {}", a.ty, b.ty),
                        )
                        .label(format!("this is a {}", b.ty));
                    Type::ERROR
                };
                mk(ty, Node::If { cond: Box::new(c), then: Box::new(a), other: Box::new(b) }, span)
            }
        }
    }

    pub(super) fn member(&mut self, base: Expr, name: String, span: Span, name_span: Span) -> Expr {
        match base.node {
            Node::Path(mut p) => {
                p.segments.push(name);
                let from_root = p.base == PathBase::Root;
                if from_root && p.segments.len() <= 2 {
                    crate::passes::check_paths::check_root_member(
                        self.schema,
                        &p.segments,
                        name_span,
                        self.diags,
                    );
                }
                // An unknown member is reported here, where the segment's own span is known.
                if let Lookup::Unknown { object_type, index, candidates } =
                    self.schema.lookup(p.base_type.as_deref(), from_root, &p.segments)
                    && index + 1 == p.segments.len()
                {
                    let seg = &p.segments[index];
                    self.diags
                        .error(
                            codes::UNKNOWN_PROPERTY,
                            name_span,
                            format!("an object of type \"{object_type}\" has no property `{seg}`"),
                        )
                        .label(format!("`{seg}` is not in the schema"))
                        .suggest(seg, candidates.iter().copied());
                }
                let ty = self.path_type(&p);
                mk(ty, Node::Path(p), span)
            }
            _ if matches!(base.ty.kind, TypeKind::Range { .. })
                && (name == "min" || name == "max") =>
            {
                let ty = Type::number_in(unit_of(&base.ty)).maybe_absent(base.ty.absent);
                let max = name == "max";
                mk(ty, Node::RangeEnd { range: Box::new(base), max }, span)
            }
            _ if base.ty.kind == TypeKind::Error => base,
            _ => {
                let d = self.diags.error(
                    codes::TYPE_MISMATCH,
                    name_span,
                    format!("a {} has no member `{name}`", base.ty),
                );
                if matches!(base.ty.kind, TypeKind::Range { .. }) {
                    d.help("a range has `.min` and `.max`");
                }
                mk(Type::ERROR, Node::Bool(false), span)
            }
        }
    }

    pub(super) fn builtin_call(
        &mut self,
        f: &str,
        args: Vec<Expr>,
        span: Span,
        name_span: Span,
    ) -> Expr {
        let Some(def) = builtins::function(f) else {
            return mk(Type::ERROR, Node::Bool(false), span);
        };
        if args.len() != def.params.len() {
            self.diags
                .error(
                    codes::ARG_COUNT,
                    name_span,
                    format!(
                        "`{f}` takes {} argument{}, but {} {} given",
                        def.params.len(),
                        if def.params.len() == 1 { "" } else { "s" },
                        args.len(),
                        if args.len() == 1 { "was" } else { "were" }
                    ),
                )
                .help(format!("{f}: {}", def.doc));
        }
        let mut absent = false;
        for (a, kind) in args.iter().zip(def.params.bytes()) {
            absent |= a.ty.absent;
            match kind {
                b'n' if !a.ty.is_numeric() => {
                    self.not_a_number(a, &format_args!("an argument of `{f}`"))
                }
                b's' if !a.ty.fits(&Type::STRING) => {
                    self.diags.error(
                        codes::TYPE_MISMATCH,
                        a.span,
                        format!("an argument of `{f}` must be a string, but this is a {}", a.ty),
                    );
                }
                _ => {}
            }
        }
        if f == "format"
            && let Some(Expr { node: Node::Str(spec), span, .. }) = args.get(1)
            && parse_spec(spec).is_none()
        {
            self.bad_spec(*span, spec);
        }
        let first_unit = args.first().and_then(|a| unit_of(&a.ty));
        let ty = match def.returns {
            Returns::SameUnit => Type::number_in(first_unit),
            Returns::Unitless => Type::number(),
            Returns::Unit(u) => Type::number_in(Some(Name::new(u))),
            Returns::String => Type::STRING,
            Returns::Colour => Type::COLOUR,
            Returns::Bool => {
                absent = false;
                Type::BOOL
            }
        };
        mk(ty.maybe_absent(absent), Node::Call { function: f.to_string(), args }, span)
    }

    pub(super) fn bad_spec(&mut self, span: Span, spec: &str) {
        self.diags
            .error(codes::BAD_FORMAT, span, format!("`{spec}` is not a format spec"))
            .help("a spec is `[0][width][.digits]`, e.g. `.1` (one decimal) or `03.0` (three digits, zero-padded)");
    }

    pub(super) fn string(&mut self, parts: &[StrPart], scope: &Scope<'a>, span: Span) -> Expr {
        if let [StrPart::Text(t)] = parts {
            return mk(Type::STRING, Node::Str(t.clone()), span);
        }
        if parts.is_empty() {
            return mk(Type::STRING, Node::Str(String::new()), span);
        }
        let mut out = Vec::new();
        let mut absent = false;
        for p in parts {
            match p {
                StrPart::Text(t) => out.push(FormatPart::Text(t.clone())),
                StrPart::Interp { expr, spec } => {
                    let e = self.lower(expr, scope);
                    self.check_showable(&e);
                    absent |= e.ty.absent;
                    let spec = spec.as_ref().and_then(|(s, sp)| {
                        let parsed = parse_spec(s);
                        if parsed.is_none() {
                            self.bad_spec(*sp, s);
                        }
                        parsed
                    });
                    out.push(FormatPart::Value { expr: e, spec });
                }
            }
        }
        // An interpolated string is never absent: an absent value shows as "—".
        let _ = absent;
        mk(Type::STRING, Node::Format(out), span)
    }

    pub(super) fn binary_type(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Type {
        let absent = a.ty.absent || b.ty.absent;
        let lenient = a.ty.is_lenient() || b.ty.is_lenient();
        match op {
            BinOp::Coalesce => {
                if !lenient && !a.ty.fits(&b.ty) {
                    self.diags
                        .error(codes::TYPE_MISMATCH, b.span, format!("the default after `??` must be a {} like the value before it, but this is a {}", a.ty.present(), b.ty))
                        .label(format!("this is a {}", b.ty));
                    return Type::ERROR;
                }
                let base = if a.ty.is_lenient() { b.ty } else { a.ty };
                let mut t = base.present().maybe_absent(b.ty.absent);
                if let (TypeKind::Number { unit: None }, Some(u)) = (&t.kind, unit_of(&b.ty)) {
                    t.kind = TypeKind::Number { unit: Some(u) };
                }
                t
            }
            BinOp::And | BinOp::Or => {
                for x in [a, b] {
                    if !x.ty.is_bool() {
                        self.diags
                            .error(
                                codes::NOT_BOOL,
                                x.span,
                                format!(
                                    "`{}` needs conditions (bool), but this is a {}",
                                    op.symbol(),
                                    x.ty
                                ),
                            )
                            .label(format!("this is a {}", x.ty));
                    }
                }
                Type::BOOL.maybe_absent(absent)
            }
            BinOp::Eq | BinOp::Ne => {
                if !lenient && !a.ty.fits(&b.ty) {
                    self.diags.error(
                        codes::TYPE_MISMATCH,
                        op_span(a, b),
                        format!("cannot compare a {} with a {}", a.ty, b.ty),
                    );
                } else {
                    self.same_unit(op, a, b);
                }
                Type::BOOL.maybe_absent(absent)
            }
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => {
                let durations = a.ty.kind == TypeKind::Duration && b.ty.kind == TypeKind::Duration;
                if !durations {
                    self.numeric_operands(a, b);
                    self.same_unit(op, a, b);
                }
                Type::BOOL.maybe_absent(absent)
            }
            BinOp::Add | BinOp::Sub => {
                if a.ty.kind == TypeKind::Duration
                    && (b.ty.kind == TypeKind::Duration || b.ty.is_lenient())
                {
                    return Type::DURATION.maybe_absent(absent);
                }
                if a.ty.kind == TypeKind::String || b.ty.kind == TypeKind::String {
                    let s = if a.ty.kind == TypeKind::String { a } else { b };
                    self.diags
                        .error(
                            codes::NOT_A_NUMBER,
                            s.span,
                            format!("a string is used as a number in `{}`", op.symbol()),
                        )
                        .label("this is a string")
                        .help("to join text, interpolate: \"{a} {b}\"");
                    return Type::ERROR;
                }
                self.numeric_operands(a, b);
                let unit = self.same_unit(op, a, b);
                Type::number_in(unit).maybe_absent(absent)
            }
            BinOp::Mul | BinOp::Div => {
                if a.ty.kind == TypeKind::Duration && b.ty.is_numeric() {
                    return Type::DURATION.maybe_absent(absent);
                }
                self.numeric_operands(a, b);
                Type::number().maybe_absent(absent)
            }
            BinOp::Range => {
                self.numeric_operands(a, b);
                let unit = self.same_unit(op, a, b);
                Type::new(TypeKind::Range { unit }).maybe_absent(absent)
            }
        }
    }

    pub(super) fn numeric_operands(&mut self, a: &Expr, b: &Expr) {
        for x in [a, b] {
            if !x.ty.is_numeric() {
                self.not_a_number(x, &"an operand");
            }
        }
    }

    /// Checks that both sides have the same unit when both have one; returns the result unit.
    pub(super) fn same_unit(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Option<Name> {
        match (unit_of(&a.ty), unit_of(&b.ty)) {
            (Some(x), Some(y)) if x != y => {
                self.diags
                    .error(
                        codes::UNIT_MISMATCH,
                        op_span(a, b),
                        format!("`{}` of {x} and {y}", op.symbol()),
                    )
                    .label(format!("{x} {} {y}", op.symbol()))
                    .help(format!(
                        "convert one side first, e.g. multiply by a factor, so both are in {x}"
                    ));
                None
            }
            (Some(x), _) | (_, Some(x)) => Some(x),
            _ => None,
        }
    }
}

fn op_span(a: &Expr, b: &Expr) -> Span {
    a.span.to(b.span)
}

/// Parses `[0][width][.precision]`.
pub fn parse_spec(s: &str) -> Option<FormatSpec> {
    let (int, prec) = match s.split_once('.') {
        Some((i, p)) => (i, Some(p)),
        None => (s, None),
    };
    if !int.chars().all(|c| c.is_ascii_digit())
        || prec.is_some_and(|p| p.is_empty() || !p.chars().all(|c| c.is_ascii_digit()))
    {
        return None;
    }
    Some(FormatSpec {
        zero: int.starts_with('0') && int.len() > 1,
        width: if int.is_empty() { None } else { int.parse().ok() },
        precision: match prec {
            Some(p) => Some(p.parse().ok()?),
            None => None,
        },
    })
}

pub(super) fn want_text(t: &Type) -> &'static str {
    if t.kind == TypeKind::Duration { "a duration" } else { "a number" }
}

/// A path the schema does not type (dynamic), given to a parameter of a value type, is read
/// as that type (a `string?` parameter reads a string), absent when it is something else.
pub(super) fn read_as(mut b: Bound, ty: &Type) -> Bound {
    let value = matches!(
        ty.kind,
        TypeKind::String | TypeKind::Number { .. } | TypeKind::Bool | TypeKind::Colour
    );
    if b.expr.ty.kind == TypeKind::Dynamic && value {
        b.expr.ty = Type { kind: ty.kind, absent: true };
    }
    b
}

/// The unit of a number or range type.
pub(super) fn unit_of(t: &Type) -> Option<Name> {
    match t.kind {
        TypeKind::Number { unit } | TypeKind::Range { unit } => unit,
        _ => None,
    }
}
