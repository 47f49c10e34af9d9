//! Operator precedence and associativity (docs/language.md, "Precedence"): each case is a
//! `let` value and its tree written with every operator bracketed.

use mocu_language::ast::{BinOp, Expr, ExprKind, Item, UnOp};
use mocu_language::{Diagnostics, FileId, parser};

fn tree(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Binary(op, a, b) => {
            // The language's words for `or` and `and`; every other operator as `symbol()`.
            let op = match op {
                BinOp::Or => "or",
                BinOp::And => "and",
                other => other.symbol(),
            };
            format!("({} {op} {})", tree(a), tree(b))
        }
        ExprKind::Unary(UnOp::Neg, a) => format!("(-{})", tree(a)),
        ExprKind::Unary(_, a) => format!("(not {})", tree(a)),
        ExprKind::Name(n) => n.clone(),
        ExprKind::Number { value, .. } => value.to_string(),
        ExprKind::Field(a, f) => format!("{}.{}", tree(a), f.name),
        ExprKind::Call(f, args) => {
            format!("{}({})", tree(f), args.iter().map(tree).collect::<Vec<_>>().join(", "))
        }
        ExprKind::If(c, a, b) => format!("(if {} then {} else {})", tree(c), tree(a), tree(b)),
        other => format!("{other:?}"),
    }
}

fn parse(value: &str) -> String {
    let mut diags = Diagnostics::new();
    let file = parser::parse(FileId(0), &format!("let x = {value}"), &mut diags);
    assert!(!diags.has_errors(), "{value}: {:?}", diags.iter().next());
    match &file.items[..] {
        [Item::Let(l)] => tree(&l.value),
        other => panic!("{value}: {other:?}"),
    }
}

#[test]
fn binary_operators_bind_loosest_first_from_range_to_multiplication() {
    for (text, expected) in [
        ("a + b * c", "(a + (b * c))"),
        ("a * b + c", "((a * b) + c)"),
        ("a .. b or c", "(a .. (b or c))"),
        ("a || b && c", "(a or (b and c))"),
        ("a and b == c", "(a and (b == c))"),
        ("a < b ?? c", "(a < (b ?? c))"),
        ("a ?? b + c", "(a ?? (b + c))"),
        ("a >= b + 1 and c != d or e <= f", "(((a >= (b + 1)) and (c != d)) or (e <= f))"),
        ("0 .. 40 * kn", "(0 .. (40 * kn))"),
    ] {
        assert_eq!(parse(text), expected, "{text}");
    }
}

#[test]
fn arithmetic_associates_left_and_coalescing_right() {
    for (text, expected) in [
        ("a - b - c", "((a - b) - c)"),
        ("a / b / c", "((a / b) / c)"),
        ("a < b < c", "((a < b) < c)"),
        ("a ?? b ?? c", "(a ?? (b ?? c))"),
        ("a ?? b ?? c + d", "(a ?? (b ?? (c + d)))"),
    ] {
        assert_eq!(parse(text), expected, "{text}");
    }
}

#[test]
fn prefixes_bind_tighter_than_every_binary_operator() {
    for (text, expected) in [
        ("-a * b", "((-a) * b)"),
        ("not a == b", "((not a) == b)"),
        ("!a and b", "((not a) and b)"),
        ("a - -b", "(a - (-b))"),
        ("- - a", "(-(-a))"),
        ("-f(x).y + 1", "((-f(x).y) + 1)"),
        ("(a + b) * c", "((a + b) * c)"),
        ("if a then b + 1 else c * 2", "(if a then (b + 1) else (c * 2))"),
    ] {
        assert_eq!(parse(text), expected, "{text}");
    }
}

#[test]
fn word_operators_need_a_word_boundary_and_minus_is_not_an_arrow() {
    for (text, expected) in [
        ("a or b", "(a or b)"),
        ("a and b", "(a and b)"),
        ("order + andy", "(order + andy)"),
        ("a-b", "(a - b)"),
    ] {
        assert_eq!(parse(text), expected, "{text}");
    }
}
