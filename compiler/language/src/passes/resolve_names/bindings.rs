//! `bind` blocks: devices, input names and kinds, binding options (E0207, E0211).

use super::*;

impl<'a> Resolver<'a, '_> {
    pub(super) fn bind(&mut self, b: &'a Bind, scope: &Scope<'a>) {
        let Some((_, kinds)) = builtins::DEVICES.iter().find(|(d, _)| *d == b.device.name) else {
            self.diags
                .error(
                    codes::UNKNOWN_INPUT,
                    b.device.span,
                    format!("there is no input device `{}`", b.device.name),
                )
                .suggest(&b.device.name, builtins::DEVICES.iter().map(|(d, _)| *d))
                .help
                .get_or_insert_with(|| "devices are `gamepad`, `keyboard` and `mouse`".into());
            return;
        };
        if let Some(shift) = &b.shift {
            let kind = if b.device.name == "keyboard" { "key" } else { "button" };
            self.input_exists(&b.device.name, kinds, kind, shift);
        }
        let all = b.bindings.iter().chain(b.modes.iter().flat_map(|(_, l)| l.iter()));
        for bnd in all {
            self.binding_options(b, bnd);
            match kinds.iter().find(|(k, _)| *k == bnd.kind.name) {
                None => {
                    self.diags
                        .error(
                            codes::UNKNOWN_INPUT,
                            bnd.kind.span,
                            format!("a {} has no `{}` inputs", b.device.name, bnd.kind.name),
                        )
                        .suggest(&bnd.kind.name, kinds.iter().map(|(k, _)| *k));
                }
                Some((kind, names)) => {
                    let ok = if *kind == "key" {
                        builtins::is_key(&bnd.input.name)
                    } else {
                        names.contains(&bnd.input.name.as_str())
                    };
                    if !ok {
                        let d = self.diags.error(
                            codes::UNKNOWN_INPUT,
                            bnd.input.span,
                            format!("there is no {} {kind} `{}`", b.device.name, bnd.input.name),
                        );
                        if *kind == "key" {
                            d.help(crate::syntax_hints::key_help(&bnd.input.name));
                        } else {
                            d.suggest(&bnd.input.name, names.iter().copied());
                        }
                    }
                }
            }
            let s = match builtins::binding_value(&bnd.kind.name) {
                Some(v) => scope.with(v, None),
                None => scope.clone(),
            };
            self.actions(&bnd.actions, &s);
        }
    }

    /// An input name of one kind exists on the device (E0207).
    pub(super) fn input_exists(
        &mut self,
        device: &str,
        kinds: &[(&str, &[&str])],
        kind: &str,
        input: &Ident,
    ) {
        let names: &[&str] = kinds.iter().find(|(k, _)| *k == kind).map_or(&[], |(_, n)| n);
        let ok = if kind == "key" {
            builtins::is_key(&input.name)
        } else {
            names.contains(&input.name.as_str())
        };
        if !ok {
            let d = self.diags.error(
                codes::UNKNOWN_INPUT,
                input.span,
                format!("there is no {device} {kind} `{}`", input.name),
            );
            if kind == "key" {
                d.help(crate::syntax_hints::key_help(&input.name));
            } else {
                d.suggest(&input.name, names.iter().copied());
            }
        }
    }

    /// Options fit the input: shaping on axes and wheels, events on buttons and keys, each
    /// at most once, one event per binding; `shift …` needs a shift input (E0211).
    pub(super) fn binding_options(&mut self, b: &Bind, bnd: &Binding) {
        let axis = builtins::binding_value(&bnd.kind.name).is_some();
        let mut seen: Vec<&str> = Vec::new();
        let mut events = 0;
        for o in &bnd.options {
            let n = o.name.name.as_str();
            let (shaping, numeric) = match n {
                "deadzone" | "expo" | "scale" | "rate" => (true, true),
                "invert" => (true, false),
                "hold" => (false, true),
                _ => (false, false),
            };
            let why = if seen.contains(&n) {
                Some(format!("`{n}` is given twice"))
            } else if shaping && !axis {
                Some(format!("`{n}` shapes an axis; a {} has no value to shape", bnd.kind.name))
            } else if !shaping && axis {
                Some(format!(
                    "`{n}` is an event of buttons and keys, not of {} {}",
                    if bnd.kind.name == "axis" { "an" } else { "a" },
                    bnd.kind.name
                ))
            } else if numeric && o.value.is_none() {
                Some(format!(
                    "`{n}` needs a value, e.g. `{n} {}`",
                    if n == "hold" { "500ms" } else { "0.1" }
                ))
            } else if !numeric && o.value.is_some() {
                Some(format!("`{n}` takes no value"))
            } else {
                None
            };
            if !shaping {
                events += 1;
            }
            seen.push(n);
            if let Some(why) = why {
                self.diags.error(codes::BAD_BINDING, o.span, why);
            } else if events > 1 {
                self.diags
                    .error(codes::BAD_BINDING, o.span, "a binding reacts to one event")
                    .help("write one binding per event: `button south -> …` and `button south double -> …`");
            }
        }
        if bnd.shift && b.shift.is_none() {
            self.diags
                .error(
                    codes::BAD_BINDING,
                    bnd.span,
                    format!(
                        "`shift` binding, but this `bind {}` names no shift input",
                        b.device.name
                    ),
                )
                .help("add e.g. `shift left_bumper` at the top of the `bind` block");
        }
    }
}
