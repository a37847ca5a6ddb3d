//! Developer tool: parse files and print the diagnostics (`cargo run -p sfc-syntax --example parse_dump FILE…`).

// A panic in a test or a developer tool is a failure report, not a crash on user input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
fn main() {
    for path in std::env::args().skip(1) {
        let text = std::fs::read_to_string(&path).expect("readable file");
        let (unit, diags) = sfc_syntax::parse(0, &text);
        let files = [sfc_diagnostics::SourceFile::new(path.clone(), text)];
        println!("{path}: {} items, {} trivia, {} diagnostics", unit.items.len(), unit.trivia.len(), diags.len());
        for d in &diags {
            print!("{}", sfc_diagnostics::render_human(d, &files, Default::default()));
        }
        if std::env::var("DUMP").is_ok() {
            println!("{unit:#?}");
        }
    }
}
