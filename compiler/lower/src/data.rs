//! Which parameters of a component carry the data its widgets show: only what feeds them
//! makes a widget stale (the layout computes `stale`/`aged` from them, the widget renderer
//! veils by them). The one copy of the rule, docs/language.md "Stale data".

use mocu_language::program::{Component, Param};
use mocu_language::types::TypeKind;

/// The parameters of `c` that carry the data a widget shows, whose staleness veils it:
/// those with no default value of number, bool or string type, optional or not
/// (`value: number?`, `text: string`). A parameter with a default is a setting (a range,
/// units, a caption, an alert's `message` and `active`). A control — a component that
/// raises an event — shows an action: only its optional numbers and booleans (a toggle's
/// `state`) carry data, never its label.
pub fn data_params(c: &Component) -> impl Iterator<Item = &Param> {
    let control = !c.events.is_empty();
    c.params.iter().filter(move |p| {
        p.default.is_none()
            && match p.ty.kind {
                TypeKind::Number { .. } | TypeKind::Bool => !control || p.ty.absent,
                TypeKind::String => !control,
                _ => false,
            }
    })
}
