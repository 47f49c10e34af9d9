//! docs/components.md is generated from the stdlib's doc comments and is never stale:
//! `UPDATE_DOCS=1 cargo test -p mocu-language --test components_doc` rewrites it.

const PAGE: &str = "../../docs/components.md";

fn stdlib() -> Vec<(String, String)> {
    let mut files: Vec<_> = std::fs::read_dir("../../stdlib")
        .expect("the stdlib folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mocu"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let name = format!("stdlib/{}", p.file_name().unwrap().to_string_lossy());
            (name, std::fs::read_to_string(&p).expect("readable"))
        })
        .collect()
}

#[test]
fn the_components_page_is_generated_from_the_stdlib_and_up_to_date() {
    let page = mocu_language::docgen::components_reference(&stdlib());
    if std::env::var("UPDATE_DOCS").is_ok_and(|v| v == "1") {
        std::fs::write(PAGE, &page).expect("writable");
    }
    let on_disk = std::fs::read_to_string(PAGE).unwrap_or_default();
    assert!(
        on_disk == page,
        "docs/components.md is stale: UPDATE_DOCS=1 cargo test -p mocu-language --test components_doc"
    );
}

#[test]
fn every_standard_component_is_in_the_reference_with_its_parameters() {
    let page = mocu_language::docgen::components_reference(&stdlib());
    for c in [
        "Dial",
        "Bar",
        "TextGauge",
        "Label",
        "Button",
        "HeadingTape",
        "Horizon",
        "ToastList",
        "AlertBanner",
        "VehicleList",
        "Map",
        "Video",
    ] {
        assert!(page.contains(&format!("### {c}\n")), "{c} is missing");
    }
    for param in
        ["| `value` | number? |", "| `range` | range | `0 .. 100` |", "| `colour` | colour |"]
    {
        assert!(page.contains(param), "{param} is missing");
    }
    // Every parameter of the main gauges says what it means.
    for (c, next) in
        [("### Dial", "### Bar"), ("### Button", "### Toggle"), ("### Label", "### HeadingTape")]
    {
        let start = page.find(c).unwrap();
        let end = page[start..].find(next).map_or(page.len(), |e| start + e);
        for row in page[start..end].lines().filter(|l| l.starts_with("| `")) {
            assert!(!row.ends_with("|  |"), "undocumented parameter in {c}: {row}");
        }
    }
}

#[test]
fn an_indented_doc_line_goes_on_with_the_parameter_above_it() {
    let text = "// A thing.\n// - size: how big it is, in px, or none when not\n//   given\n// More about it.\ncomponent Thing(size: number = 1) {\n}\n";
    let page =
        mocu_language::docgen::components_reference(&[("stdlib/thing.mocu".into(), text.into())]);
    assert!(
        page.contains("| `size` | number | `1` | how big it is, in px, or none when not given |"),
        "{page}"
    );
    assert!(
        page.contains("A thing.\nMore about it.") || page.contains("A thing. More about it."),
        "{page}"
    );
    assert!(!page.contains("\n  given"), "{page}");
}

/// Every standard component used without its `use` gets the help naming its file, whichever
/// file of stdlib/ it is in (a file left out of the hints' list once gave `ControlHolder`
/// "e.g. stdlib/gauges.mocu").
#[test]
fn a_standard_component_used_without_its_file_is_told_which_file_to_use() {
    use mocu_language::{Diagnostics, FsLoader, SourceMap};
    let mut checked = 0;
    for (file, text) in stdlib() {
        for line in text.lines() {
            let Some(rest) = line.strip_prefix("component ") else { continue };
            let name: String =
                rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            let layout = format!(
                "window w {{ rect 0 0 100 100 }}\nin w {{\n    x: {name} {{ at 0 0 10 10 }}\n}}\n"
            );
            let (mut sources, mut diags) = (SourceMap::default(), Diagnostics::default());
            let _ = mocu_language::check_layout(
                "t.mocu",
                layout,
                &FsLoader,
                None,
                &mut sources,
                &mut diags,
            );
            let want = format!("`{name}` is in {file}: add `use \"{file}\"`");
            let helps: Vec<String> = diags.iter().filter_map(|d| d.help.clone()).collect();
            assert!(helps.iter().any(|h| h.contains(&want)), "{name}: {helps:?}");
            checked += 1;
        }
    }
    assert!(checked >= 15, "only {checked} components found");
}
