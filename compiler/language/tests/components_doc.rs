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
