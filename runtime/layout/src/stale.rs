//! Staleness: a widget is stale when the data it shows is old, never merely unchanged.
//!
//! Each widget gets an output `stale` (a bool property of the widget object, drawn by the
//! renderer as a veil and a STALE tag): true while any vehicle it reads from says its data
//! is old — the vehicle's `stale` or `link_lost` flag, which the vehicle's protocol module
//! keeps (the simulator and MAVLink raise both when the link is lost, lower them when it is
//! back). It is an ordinary compiled expression over those flags, so it follows them through
//! the same path watches as every other output: no timer, no polling, nothing to do while
//! nothing changes. A vehicle is the object `root.vehicles.<name>` a path goes through, or a
//! template's object (`for each v in root.vehicles …`). A stopped boat with a good link
//! writes the same speed over and over and is never stale.

use mocu_jit as jit;
use mocu_lower::{Base, Lowerer, Source};

/// Flags of a vehicle that say its data is old.
pub const FLAGS: [&str; 2] = ["stale", "link_lost"];

/// The vehicles (base and object names) the slots of `lw` read from.
fn vehicles(lw: &Lowerer) -> Vec<(Base, Vec<String>)> {
    let mut out: Vec<(Base, Vec<String>)> = Vec::new();
    for (src, _) in &lw.slots {
        let Source::Path { base, objects, .. } = src else { continue };
        let v = match base {
            Base::Root if objects.len() >= 2 && objects[0] == "vehicles" => {
                (Base::Root, objects[..2].to_vec())
            }
            Base::Var(name) => (Base::Var(name.clone()), Vec::new()),
            _ => continue,
        };
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

/// The `stale` output of a widget whose outputs were lowered with `lw`: absent flags count
/// as fresh. `None` when the widget reads no vehicle.
pub(crate) fn widget_stale(lw: &mut Lowerer) -> Option<jit::Expr> {
    let mut out: Option<jit::Expr> = None;
    for (base, objects) in vehicles(lw) {
        for flag in FLAGS {
            let src = Source::Path {
                base: base.clone(),
                objects: objects.clone(),
                property: flag.into(),
            };
            lw.slots.push((src, jit::Ty::Bool));
            let input = jit::Expr::Input((lw.slots.len() - 1) as u32, jit::Ty::Bool);
            let x = jit::Expr::Coalesce(Box::new(input), Box::new(jit::Expr::Bool(false)));
            out = Some(match out {
                None => x,
                Some(prev) => jit::Expr::Or(Box::new(prev), Box::new(x)),
            });
        }
    }
    out
}
