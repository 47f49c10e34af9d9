//! The IR's documented semantics, by example, on both backends.

#![forbid(unsafe_code)]
use mocu_jit::ir::MAX_DEPTH;
use mocu_jit::*;
use std::sync::Arc;

fn num(x: f64) -> Expr {
    Expr::Num(x)
}
fn b(e: Expr) -> Box<Expr> {
    Box::new(e)
}
fn input(i: u32, t: Ty) -> Expr {
    Expr::Input(i, t)
}

/// Evaluates `e` with the JIT and the interpreter; both must agree; returns the result.
fn eval(e: Expr, inputs: &[(Ty, Slot)]) -> Out {
    let f = Function::new(inputs.iter().map(|i| i.0).collect(), vec![e]);
    let unit = compile(std::slice::from_ref(&f)).expect("compiles");
    let interp = Interpreter::new(&[f]).expect("checks");
    let slots: Vec<Slot> = inputs.iter().map(|i| i.1).collect();
    let mut results = Vec::new();
    for ev in [&unit as &dyn Evaluate, &interp] {
        let mut ctx = ev.context();
        let mut out = [Slot::ABSENT];
        ev.call(0, &slots, &mut out, &mut ctx);
        results.push(out[0].decode(ev.output_types(0)[0], &ctx));
    }
    assert_eq!(results[0], results[1], "JIT and interpreter disagree");
    results.pop().unwrap()
}

#[test]
fn arithmetic_on_present_numbers_is_ieee() {
    let e = Expr::Arith(Arith::Mul, b(input(0, Ty::Num)), b(num(1.94384)));
    assert_eq!(eval(e, &[(Ty::Num, Slot::num(10.0))]), Out::Num(10.0 * 1.94384));
}

#[test]
fn arithmetic_on_absent_is_absent() {
    let e = Expr::Arith(Arith::Add, b(input(0, Ty::Num)), b(num(1.0)));
    assert_eq!(eval(e, &[(Ty::Num, Slot::ABSENT)]), Out::Absent);
}

#[test]
fn division_by_zero_and_nan_are_absent_not_silent_numbers() {
    let div = Expr::Arith(Arith::Div, b(num(1.0)), b(input(0, Ty::Num)));
    assert_eq!(eval(div, &[(Ty::Num, Slot::num(0.0))]), Out::Absent);
    let sqrt = Expr::Call(Builtin::Sqrt, vec![num(-1.0)]);
    assert_eq!(eval(sqrt, &[]), Out::Absent);
    let huge = Expr::Arith(Arith::Mul, b(num(1e300)), b(num(1e300)));
    assert_eq!(eval(huge, &[]), Out::Absent, "overflow to infinity is absent");
    assert_eq!(Slot::num(f64::NAN), Slot::ABSENT, "a NaN input is absent");
}

#[test]
fn coalesce_gives_the_first_present_value() {
    let e = Expr::Coalesce(b(input(0, Ty::Num)), b(num(0.0)));
    assert_eq!(eval(e.clone(), &[(Ty::Num, Slot::ABSENT)]), Out::Num(0.0));
    assert_eq!(eval(e, &[(Ty::Num, Slot::num(0.3))]), Out::Num(0.3));
}

#[test]
fn and_or_follow_kleene_logic_with_absent() {
    let absent = || input(0, Ty::Bool);
    let ins = [(Ty::Bool, Slot::ABSENT)];
    assert_eq!(eval(Expr::And(b(Expr::Bool(false)), b(absent())), &ins), Out::Bool(false));
    assert_eq!(eval(Expr::And(b(Expr::Bool(true)), b(absent())), &ins), Out::Absent);
    assert_eq!(eval(Expr::Or(b(absent()), b(Expr::Bool(true))), &ins), Out::Bool(true));
    assert_eq!(eval(Expr::Or(b(absent()), b(Expr::Bool(false))), &ins), Out::Absent);
}

#[test]
fn if_with_an_absent_condition_is_absent() {
    let e =
        Expr::If(b(input(0, Ty::Bool)), b(Expr::Str("DISARM".into())), b(Expr::Str("ARM".into())));
    assert_eq!(eval(e.clone(), &[(Ty::Bool, Slot::bool(true))]), Out::Str("DISARM".into()));
    assert_eq!(eval(e.clone(), &[(Ty::Bool, Slot::bool(false))]), Out::Str("ARM".into()));
    assert_eq!(eval(e, &[(Ty::Bool, Slot::ABSENT)]), Out::Absent);
}

#[test]
fn interpolated_strings_format_numbers_and_are_absent_if_a_part_is() {
    let spec = NumFormat { zero: true, width: Some(3), precision: Some(0) };
    let e = Expr::Format(vec![
        Piece::Text("HDG ".into()),
        Piece::Num(input(0, Ty::Num), spec),
        Piece::Text("°".into()),
    ]);
    assert_eq!(eval(e.clone(), &[(Ty::Num, Slot::num(7.4))]), Out::Str("HDG 007°".into()));
    assert_eq!(eval(e, &[(Ty::Num, Slot::ABSENT)]), Out::Absent);
    let one = NumFormat { precision: Some(1), ..NumFormat::default() };
    let kn = Expr::Format(vec![Piece::Num(num(12.345), one), Piece::Text(" kn".into())]);
    assert_eq!(eval(kn, &[]), Out::Str("12.3 kn".into()));
}

#[test]
fn string_inputs_compare_by_content() {
    let mut ctx = EvalCtx::new(&[]);
    let s = Slot::str(&mut ctx, Arc::from("usv"));
    let e = Expr::Cmp(Cmp::Eq, b(input(0, Ty::Str)), b(Expr::Str("usv".into())));
    // Inputs carry handles into the caller's context: build the context the same way.
    let f = Function::new(vec![Ty::Str], vec![e]);
    for ev in [
        Box::new(compile(std::slice::from_ref(&f)).unwrap()) as Box<dyn Evaluate>,
        Box::new(Interpreter::new(std::slice::from_ref(&f)).unwrap()),
    ] {
        let mut ctx = ev.context();
        let s2 = Slot::str(&mut ctx, Arc::from("usv"));
        let mut out = [Slot::ABSENT];
        ev.call(0, &[s2], &mut out, &mut ctx);
        assert_eq!(out[0].decode(Ty::Bool, &ctx), Out::Bool(true));
    }
    assert!(s.is_present());
}

#[test]
fn builtins_behave_as_documented() {
    let call = |f, args: Vec<f64>| eval(Expr::Call(f, args.into_iter().map(num).collect()), &[]);
    assert_eq!(call(Builtin::Round, vec![2.5]), Out::Num(3.0), "half away from zero");
    assert_eq!(call(Builtin::Round, vec![-2.5]), Out::Num(-3.0));
    assert_eq!(call(Builtin::Mod, vec![-1.0, 360.0]), Out::Num(359.0), "sign of the divisor");
    assert_eq!(call(Builtin::Clamp, vec![5.0, 0.0, 1.0]), Out::Num(1.0));
    assert_eq!(call(Builtin::Deadzone, vec![0.05, 0.1]), Out::Num(0.0));
    assert_eq!(call(Builtin::Deadzone, vec![1.0, 0.1]), Out::Num(1.0), "full scale still reached");
    assert_eq!(call(Builtin::Deadzone, vec![-0.75, 0.5]), Out::Num(-0.5));
    assert_eq!(call(Builtin::Deg, vec![std::f64::consts::PI]), Out::Num(180.0));
    assert_eq!(call(Builtin::Lerp, vec![10.0, 20.0, 0.25]), Out::Num(12.5));
    assert_eq!(call(Builtin::Rgb, vec![255.0, 128.0, 0.0]), Out::Color(0xff8000ff));
    assert_eq!(call(Builtin::Rgba, vec![0.0, 0.0, 0.0, 0.5]), Out::Color(0x00000080));
    assert_eq!(call(Builtin::Min, vec![-0.0, 0.0]).clone(), Out::Num(0.0));
}

#[test]
fn many_outputs_of_one_function_are_all_written() {
    let f = Function {
        inputs: vec![Ty::Num],
        locals: vec![],
        outputs: vec![
            Expr::Arith(Arith::Add, b(input(0, Ty::Num)), b(num(1.0))),
            Expr::Cmp(Cmp::Gt, b(input(0, Ty::Num)), b(num(35.0))),
            Expr::Present(b(input(0, Ty::Num))),
        ],
    };
    let unit = compile(&[f]).unwrap();
    let mut ctx = unit.context();
    let mut out = [Slot::ABSENT; 3];
    unit.call(0, &[Slot::num(40.0)], &mut out, &mut ctx);
    assert_eq!(out[0].decode(Ty::Num, &ctx), Out::Num(41.0));
    assert_eq!(out[1].decode(Ty::Bool, &ctx), Out::Bool(true));
    assert_eq!(out[2].decode(Ty::Bool, &ctx), Out::Bool(true));
}

#[test]
fn ill_typed_ir_is_refused_before_code_generation() {
    let bad = Function {
        inputs: vec![],
        locals: vec![],
        outputs: vec![Expr::Arith(Arith::Add, b(Expr::Bool(true)), b(num(1.0)))],
    };
    assert!(matches!(compile(std::slice::from_ref(&bad)), Err(JitError::Ir(_))));
    assert!(Interpreter::new(&[bad]).is_err());
}

#[test]
fn comparing_absent_strings_is_absent_even_with_no_string_in_the_context() {
    // Regression: the compiled comparison ran the string helper on an absent operand's
    // meaningless handle, which indexed an empty string table and aborted.
    let e = Expr::Cmp(Cmp::Eq, b(input(0, Ty::Str)), b(input(1, Ty::Str)));
    assert_eq!(eval(e, &[(Ty::Str, Slot::ABSENT), (Ty::Str, Slot::ABSENT)]), Out::Absent);
}

/// Evaluates a function's one output under both backends (they must agree).
fn eval_function(f: Function, inputs: &[Slot]) -> Out {
    let unit = compile(std::slice::from_ref(&f)).expect("compiles");
    let interp = Interpreter::new(&[f]).expect("checks");
    let mut results = Vec::new();
    for ev in [&unit as &dyn Evaluate, &interp] {
        let mut ctx = ev.context();
        let mut out = [Slot::ABSENT];
        ev.call(0, inputs, &mut out, &mut ctx);
        results.push(out[0].decode(ev.output_types(0)[0], &ctx));
    }
    assert_eq!(results[0], results[1], "JIT and interpreter disagree");
    results.pop().unwrap()
}

#[test]
fn a_local_is_computed_once_and_read_by_every_use() {
    // 60 doubling `let`s: local i is local i-1 + local i-1. As a tree this is 2^60 nodes;
    // as locals, 60 additions.
    let local = |i: u32| Expr::Local(i, Ty::Num);
    let mut locals = vec![input(0, Ty::Num)];
    for i in 1..=60 {
        locals.push(Expr::Arith(Arith::Add, b(local(i - 1)), b(local(i - 1))));
    }
    let f = Function { inputs: vec![Ty::Num], locals, outputs: vec![local(60)] };
    assert_eq!(eval_function(f, &[Slot::num(3.0)]), Out::Num(3.0 * 2f64.powi(60)));
}

#[test]
fn an_absent_input_makes_every_local_built_on_it_absent() {
    let locals = vec![
        Expr::Arith(Arith::Mul, b(input(0, Ty::Num)), b(num(2.0))),
        Expr::Coalesce(b(Expr::Local(0, Ty::Num)), b(num(-1.0))),
    ];
    let f = Function { inputs: vec![Ty::Num], locals, outputs: vec![Expr::Local(1, Ty::Num)] };
    assert_eq!(eval_function(f, &[Slot::ABSENT]), Out::Num(-1.0));
}

#[test]
fn a_local_that_reads_a_later_local_or_the_wrong_type_is_refused() {
    let forward = Function {
        inputs: vec![],
        locals: vec![Expr::Local(1, Ty::Num), num(1.0)],
        outputs: vec![Expr::Local(0, Ty::Num)],
    };
    let wrong_type = Function {
        inputs: vec![],
        locals: vec![Expr::Bool(true)],
        outputs: vec![Expr::Local(0, Ty::Num)],
    };
    for f in [forward, wrong_type] {
        assert!(matches!(compile(std::slice::from_ref(&f)), Err(JitError::Ir(_))));
        assert!(Interpreter::new(&[f]).is_err());
    }
}

/// `n` additions nested in one another, built without recursion.
fn nested_adds(n: usize) -> Expr {
    let mut e = input(0, Ty::Num);
    for _ in 0..n {
        e = Expr::Arith(Arith::Add, b(e), b(num(1.0)));
    }
    e
}

#[test]
fn ir_nested_deeper_than_the_limit_is_refused_cleanly_by_both_backends() {
    // Built directly, bypassing the checker's 256-level limit: both backends and the type
    // check must refuse it with an error instead of overflowing the stack, and dropping it
    // must not overflow either (this test thread has a 2 MiB stack).
    for (outputs, locals) in [
        (vec![nested_adds(100_000)], vec![]),
        (vec![Expr::Local(0, Ty::Num)], vec![nested_adds(100_000)]),
    ] {
        let f = Function { inputs: vec![Ty::Num], locals, outputs };
        match compile(std::slice::from_ref(&f)) {
            Err(JitError::Ir(e)) => assert!(e.0.contains("levels deep"), "{e}"),
            Err(e) => panic!("refused for another reason: {e}"),
            Ok(_) => panic!("compiled a 100,000-level expression"),
        }
        assert!(Interpreter::new(std::slice::from_ref(&f)).is_err());
        assert!(f.check().is_err());
    }
    assert!(nested_adds(100_000).check(&[Ty::Num]).is_err());
}

#[test]
fn ir_at_the_depth_limit_runs_on_both_backends() {
    let e = nested_adds(MAX_DEPTH - 1);
    assert_eq!(eval(e, &[(Ty::Num, Slot::num(0.0))]), Out::Num((MAX_DEPTH - 1) as f64));
}
