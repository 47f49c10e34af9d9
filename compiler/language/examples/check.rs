//! `cargo run -p mocu-language --example check -- FILE...`: the checker without the CLI;
//! prints the diagnostics and a summary of each checked program.
fn main() {
    let mut sources = mocu_language::SourceMap::new();
    let mut diags = mocu_language::Diagnostics::new();
    for p in std::env::args().skip(1) {
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        if let Some(b) =
            mocu_language::check_path(&p, text, &mocu_language::FsLoader, &mut sources, &mut diags)
        {
            for l in &b.layouts {
                let pr = &l.program;
                println!(
                    "{}: {} windows, {} widgets, {} components, {} bindings, {} menus, {} watches, {} templates",
                    l.path,
                    pr.windows.len(),
                    pr.widgets.len(),
                    pr.components.len(),
                    pr.bindings.len(),
                    pr.menus.len(),
                    pr.watches.len(),
                    pr.templates.len()
                );
            }
        }
    }
    diags.sort();
    print!("{}", mocu_language::render::human(&sources, &diags.into_vec()));
}
