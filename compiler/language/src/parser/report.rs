//! A syntax error from pest as a diagnostic: what was expected, in the user's words, and the
//! help of `syntax_hints.rs`.

use super::{Rule, first_word};
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::source::{FileId, Span};

pub(super) fn report_pest_error(
    file: FileId,
    text: &str,
    offset: usize,
    src: &str,
    e: &pest::error::Error<Rule>,
    diags: &mut Diagnostics,
) {
    use pest::error::{ErrorVariant, InputLocation};
    let pos = match e.location {
        InputLocation::Pos(p) => p,
        InputLocation::Span((s, _)) => s,
    };
    let found = found_token(&src[pos.min(src.len())..]);
    let span = Span::new(
        file,
        offset + pos,
        offset + pos + found.len().max(1).min(src.len().saturating_sub(pos).max(1)),
    );
    let (mut message, mut help) = match &e.variant {
        ErrorVariant::ParsingError { positives, .. } => describe_expected(positives, &found),
        ErrorVariant::CustomError { message } => (message.clone(), None),
    };
    let before = &src[..pos.min(src.len())];
    let after = &src[pos.min(src.len())..];
    let item = crate::syntax_hints::inner_item(first_word(src), before);
    if let Some((m, h)) = crate::syntax_hints::hint(item, before, &found, &message, after) {
        message = m.unwrap_or(message);
        help = Some(h);
    }
    let d = diags.error(codes::SYNTAX, span, message);
    if found.is_empty() {
        d.label("the item ends here");
    }
    if found == "}"
        && let Some(open) = crate::syntax_hints::opening_of(before)
    {
        let line = text[..offset + open].matches('\n').count() + 1;
        let head = before[..=open].rsplit('\n').next().unwrap_or("").trim();
        let note = format!("this `}}` closes `{head}` from line {line}");
        if d.help.is_none() {
            d.help(note.clone());
        }
        d.label(note);
    }
    if let Some(h) = help {
        d.help(h);
    }
}

fn found_token(rest: &str) -> String {
    let t = first_word(rest);
    t.to_string()
}

fn describe_expected(positives: &[Rule], found: &str) -> (String, Option<String>) {
    let mut names: Vec<&str> = Vec::new();
    let mut operator = false;
    for r in positives {
        let name = match r {
            Rule::EOI => "the end of the item",
            Rule::ident => "a name",
            Rule::expr
            | Rule::if_expr
            | Rule::paren
            | Rule::boolean
            | Rule::self_ref
            | Rule::colour => "an expression",
            Rule::number | Rule::geom => "a number",
            Rule::string => "a string",
            Rule::rect_prop => "`rect`",
            Rule::anchor_prop | Rule::anchor_key => "`anchor`",
            Rule::anchor_name => "an anchor (`top-left`, `bottom-right`, `centre`, …)",
            Rule::design_key => "`design`",
            Rule::named_prop => "a property",
            Rule::at_prop => "`at`",
            Rule::on_prop => "`on`",
            Rule::widget => "a widget",
            Rule::param | Rule::value_param | Rule::event_param => "a parameter",
            Rule::type_name => "a type",
            Rule::primitive | Rule::style | Rule::style_key => "a drawing primitive",
            Rule::binding => "a binding",
            Rule::input_name => "an input name",
            Rule::menu_entry => "`item`",
            Rule::set_action
            | Rule::call_action
            | Rule::swap_action
            | Rule::show_action
            | Rule::hide_action
            | Rule::alert_action
            | Rule::mode_action
            | Rule::select_action => {
                "an action (`set`, `call`, `swap`, `show`, `hide`, `alert`, `mode` or `select`)"
            }
            Rule::binding_opt | Rule::opt_key | Rule::opt_value => "a binding option or `->`",
            Rule::shift_decl | Rule::mode_block | Rule::shift_mark => "a binding",
            Rule::infix | Rule::field | Rule::index | Rule::call_args => {
                operator = true;
                continue;
            }
            Rule::neg | Rule::not_op | Rule::term | Rule::primary => "an expression",
            Rule::use_item
            | Rule::let_item
            | Rule::window_item
            | Rule::in_item
            | Rule::component_item
            | Rule::bind_item
            | Rule::menu_item
            | Rule::watch_item
            | Rule::each_item
            | Rule::design_item => "an item",
            Rule::str_text | Rule::str_escape | Rule::interp => "the end of the string (`\"`)",
            Rule::fmt_spec | Rule::fmt_body => "`}`",
            _ => "something else",
        };
        if !names.contains(&name) {
            names.push(name);
        }
    }
    if operator && names.is_empty() {
        names.push("an operator");
    }
    let expected = match names.len() {
        0 => "something else".to_string(),
        1 => names[0].to_string(),
        _ => format!("{} or {}", names[..names.len() - 1].join(", "), names[names.len() - 1]),
    };
    let found_text =
        if found.is_empty() { "the end of the item".to_string() } else { format!("`{found}`") };
    let help = if names.contains(&"the end of the item") {
        Some("is an operator or a `}` missing before this, or is this word misspelt?".to_string())
    } else if found.is_empty() {
        Some("the item is unfinished: something is missing before the next item".to_string())
    } else {
        None
    };
    (format!("expected {expected}, found {found_text}"), help)
}
