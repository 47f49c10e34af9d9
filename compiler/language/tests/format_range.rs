//! Formatting a range (`format::range`): the items it touches, and nothing else.

use mocu_language::format::{self, FormatError, range::format_range};
use mocu_language::{Diagnostics, FileId};
use std::path::Path;

fn fmt(text: &str) -> String {
    format::format_source(FileId(0), text, &mut Diagnostics::new()).expect("formats")
}

fn apply(text: &str, edits: &[(std::ops::Range<usize>, String)]) -> String {
    let mut out = text.to_string();
    for (r, new) in edits.iter().rev() {
        out.replace_range(r.clone(), new);
    }
    out
}

const MESSY: &str =
    "let   a =    1\n\nwindow w {layer a   rect 0 0 10 10}\n\n// kept as it is\nlet  b  =  a+1\n";

#[test]
fn a_range_inside_one_item_formats_that_item_and_leaves_the_others() {
    let inside = MESSY.find("layer").unwrap();
    let edits = format_range(FileId(0), MESSY, inside..inside + 3, &mut Diagnostics::new());
    let edits = edits.expect("formats");
    assert_eq!(edits.len(), 1);
    let (r, new) = &edits[0];
    assert_eq!(&MESSY[r.clone()], "window w {layer a   rect 0 0 10 10}");
    let out = apply(MESSY, &edits);
    assert!(out.starts_with("let   a =    1\n") && out.ends_with("let  b  =  a+1\n"), "{out}");
    assert!(fmt(MESSY).contains(new.as_str()), "the item as the whole file's formatting has it");
}

#[test]
fn a_range_over_two_items_gives_one_edit_each_and_an_empty_range_its_item() {
    let (a, b) = (MESSY.find("=    1").unwrap(), MESSY.find("a+1").unwrap());
    let edits = format_range(FileId(0), MESSY, a..b, &mut Diagnostics::new()).expect("formats");
    assert_eq!(edits.len(), 3);
    let edits = format_range(FileId(0), MESSY, b..b, &mut Diagnostics::new()).expect("formats");
    assert_eq!(apply(MESSY, &edits), MESSY.replace("let  b  =  a+1", "let b = a + 1"));
}

#[test]
fn a_formatted_file_or_a_range_between_items_gives_no_edit() {
    let once = fmt(MESSY);
    assert_eq!(format_range(FileId(0), &once, 0..once.len(), &mut Diagnostics::new()), Ok(vec![]));
    let gap = MESSY.find("// kept").unwrap();
    assert_eq!(format_range(FileId(0), MESSY, gap..gap + 4, &mut Diagnostics::new()), Ok(vec![]));
}

#[test]
fn a_file_with_syntax_errors_is_not_formatted_in_part_either() {
    let mut d = Diagnostics::new();
    assert_eq!(
        format_range(FileId(0), "let a = (1 +\nlet b = 2\n", 0..3, &mut d),
        Err(FormatError::Syntax)
    );
    assert!(d.has_errors());
}

#[test]
fn every_item_formatted_in_part_gives_the_whole_files_formatting_over_the_layouts() {
    let mut n = 0;
    for dir in ["../../layouts", "../../stdlib"] {
        let mut paths: Vec<_> = std::fs::read_dir(Path::new(dir))
            .expect("the folder")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "mocu"))
            .collect();
        paths.sort();
        for p in paths {
            let text = std::fs::read_to_string(&p).expect("readable");
            let edits = format_range(FileId(0), &text, 0..text.len(), &mut Diagnostics::new());
            let out = apply(&text, &edits.expect("formats"));
            assert_eq!(fmt(&out), fmt(&text), "{}", p.display());
            n += 1;
        }
    }
    assert!(n > 5, "the layouts are missing");
}
