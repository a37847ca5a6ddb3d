//! Renders the SVG of every example chart (and every `tests/svg` fixture) to PNG with resvg
//! and compares it pixel by pixel with the committed reference image in `tests/png/`
//! (rewritten with `UPDATE_EXPECT=1`). Needs DejaVu Sans: without the font file the test is
//! skipped with a message, unless `CI` is set, where it fails.

mod common;

use common::*;
use resvg::tiny_skia::{Pixmap, Transform};
use resvg::usvg;
use sfc_render::{layout, svg, SvgOptions};
use std::path::{Path, PathBuf};

const FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
/// A pixel differs when a channel differs by more than this.
const CHANNEL_TOLERANCE: u8 = 24;
/// At most this share of the pixels may differ (anti-aliasing of another resvg build).
const MAX_DIFFERING: f64 = 0.002;

fn render(svg_text: &str, font: &[u8]) -> Pixmap {
    let mut opts = usvg::Options::default();
    opts.fontdb_mut().load_font_data(font.to_vec());
    let tree = usvg::Tree::from_str(svg_text, &opts).expect("the SVG parses");
    let size = tree.size().to_int_size();
    let mut pixmap = Pixmap::new(size.width(), size.height()).expect("non-empty drawing");
    resvg::render(&tree, Transform::default(), &mut pixmap.as_mut());
    pixmap
}

fn compare(name: &str, got: &Pixmap, reference: &Path) -> Result<(), String> {
    let want = Pixmap::load_png(reference)
        .map_err(|e| format!("{name}: cannot read {} ({e}); UPDATE_EXPECT=1 writes it", reference.display()))?;
    if (want.width(), want.height()) != (got.width(), got.height()) {
        return Err(format!(
            "{name}: size {}x{} differs from the reference {}x{}",
            got.width(),
            got.height(),
            want.width(),
            want.height()
        ));
    }
    let differing = got
        .data()
        .chunks(4)
        .zip(want.data().chunks(4))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > CHANNEL_TOLERANCE))
        .count();
    let total = (got.width() * got.height()) as usize;
    if differing as f64 > MAX_DIFFERING * total as f64 {
        return Err(format!("{name}: {differing} of {total} pixels differ from {}", reference.display()));
    }
    Ok(())
}

fn sources() -> Vec<(String, PathBuf)> {
    let mut out: Vec<(String, PathBuf)> =
        st_files(&repo_dir().join("examples")).into_iter().map(|p| ("example".to_string(), p)).collect();
    out.extend(st_files(&crate_dir().join("tests/svg")).into_iter().map(|p| ("svg".to_string(), p)));
    out
}

#[test]
fn png_references() {
    let font = match std::fs::read(FONT) {
        Ok(f) => f,
        Err(e) => {
            assert!(std::env::var_os("CI").is_none(), "{FONT} is needed in CI: {e}");
            eprintln!("skipping the PNG comparison: {FONT} cannot be read ({e})");
            return;
        }
    };
    let dir = crate_dir().join("tests/png");
    let mut failures = Vec::new();
    let mut count = 0;
    for (prefix, path) in sources() {
        let text = std::fs::read_to_string(&path).expect("UTF-8 source");
        let charts = charts(&path.display().to_string(), &text);
        for (i, chart) in charts.iter().enumerate() {
            let name = format!("{prefix}-{}", stem(&path, &charts, i));
            let png = dir.join(format!("{name}.png"));
            let pixmap = render(&svg(chart, &layout(chart), &SvgOptions::default()), &font);
            count += 1;
            if update() {
                pixmap.save_png(&png).expect("write the reference image");
            } else if let Err(e) = compare(&name, &pixmap, &png) {
                failures.push(e);
            }
        }
    }
    assert!(count >= 10, "only {count} charts rendered");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The comparison notices a change: a drawing with one step moved is not the reference.
#[test]
fn png_comparison_detects_changes() {
    let Ok(font) = std::fs::read(FONT) else {
        assert!(std::env::var_os("CI").is_none(), "{FONT} is needed in CI");
        eprintln!("skipping: {FONT} cannot be read");
        return;
    };
    let path = repo_dir().join("examples/blinker/blinker.st");
    let text = std::fs::read_to_string(&path).expect("example");
    let chart = &charts("blinker.st", &text)[0];
    let mut l = layout(chart);
    let original = render(&svg(chart, &l, &SvgOptions::default()), &font);
    let tmp = std::env::temp_dir().join(format!("sfc-render-png-{}.png", std::process::id()));
    original.save_png(&tmp).expect("write");
    assert!(compare("same", &original, &tmp).is_ok());
    l.steps[1].rect.x += 40.0;
    let moved = render(&svg(chart, &l, &SvgOptions::default()), &font);
    let _ = std::fs::remove_file(&tmp);
    original.save_png(&tmp).expect("write");
    let result = compare("moved", &moved, &tmp);
    let _ = std::fs::remove_file(&tmp);
    assert!(result.is_err(), "a moved step went unnoticed");
}
