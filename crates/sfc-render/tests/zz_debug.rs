mod common;
#[test]
fn debug() {
    let text = std::fs::read_to_string(std::env::var("F").unwrap()).unwrap();
    let checked = sfc_model::check_source(0, "f.st", &text, &Default::default());
    let chart = &checked.charts[0];
    let l = sfc_render::layout(chart); println!("{:?}", l.kind);
}
