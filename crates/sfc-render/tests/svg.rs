//! Snapshot tests of the SVG text: every chart of `tests/svg/*.st` is laid out and drawn, and
//! the result compared with `tests/svg/<file>[.<POU>].svg` (rewritten with `UPDATE_EXPECT=1`).
//! Each fixture names the layout it must get in its first comment (`layout: structured`), and
//! every layout must pass the geometric checks of `common::check_layout`.

mod common;

use common::*;
use sfc_render::{layout, svg, LayoutKind, SvgOptions};

fn expected_kind(text: &str) -> Option<LayoutKind> {
    let line = text.lines().find(|l| l.contains("layout:"))?;
    let word = line.split("layout:").nth(1)?.split_whitespace().next()?;
    match word {
        "structured" => Some(LayoutKind::Structured),
        "layered" => Some(LayoutKind::Layered),
        "stored" => Some(LayoutKind::Stored),
        _ => None,
    }
}

#[test]
fn svg_snapshots() {
    let dir = crate_dir().join("tests/svg");
    let files = st_files(&dir);
    assert!(files.len() >= 6, "fixtures missing in {}", dir.display());
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).expect("fixture is UTF-8");
        let charts = charts(&path.display().to_string(), &text);
        assert!(!charts.is_empty(), "{}: no chart", path.display());
        let want_kind = expected_kind(&text).unwrap_or_else(|| panic!("{}: no `layout:` line", path.display()));
        for (i, chart) in charts.iter().enumerate() {
            let l = layout(chart);
            assert_eq!(l.kind, want_kind, "{}: {}", path.display(), chart.pou);
            if let Err(e) = check_layout(chart, &l) {
                failures.push(format!("{} ({}): {e}", path.display(), chart.pou));
            }
            let out = svg(chart, &l, &SvgOptions::default());
            // The same input gives the same bytes.
            assert_eq!(out, svg(chart, &layout(chart), &SvgOptions::default()));
            let file = dir.join(format!("{}.svg", stem(path, &charts, i)));
            if update() {
                std::fs::write(&file, &out).expect("write snapshot");
            } else {
                match std::fs::read_to_string(&file) {
                    Ok(want) if want == out => {}
                    Ok(_) => failures.push(format!("{} differs (UPDATE_EXPECT=1 rewrites it)", file.display())),
                    Err(_) => failures.push(format!("{} is missing (UPDATE_EXPECT=1 writes it)", file.display())),
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The drawing contains what the IEC look asks for: a double frame for the initial step,
/// double lines for simultaneous branches, conditions and action blocks as text.
#[test]
fn svg_contains_the_iec_elements() {
    let text = std::fs::read_to_string(crate_dir().join("tests/svg/simultaneous.st")).expect("fixture");
    let chart = &charts("simultaneous.st", &text)[0];
    let l = layout(chart);
    let out = svg(chart, &l, &SvgOptions::default());
    assert!(out.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\""));
    assert!(out.trim_end().ends_with("</svg>"));
    // Idle is initial: two frames in its group.
    let idle = out.split("<g id=\"step-0\">").nth(1).and_then(|s| s.split("</g>").next()).expect("step group");
    assert_eq!(idle.matches("<rect").count(), 2, "{idle}");
    let left = out.split("<g id=\"step-1\">").nth(1).and_then(|s| s.split("</g>").next()).expect("step group");
    assert_eq!(left.matches("<rect").count(), 1, "{left}");
    // One simultaneous divergence and one convergence: two double lines.
    let doubles = l.branches.iter().filter(|b| b.kind.is_double()).count();
    assert_eq!(doubles, 2);
    assert!(out.contains(">Start</text>"));
    assert!(out.contains(">Valve</text>") && out.contains(">S</text>"));
    // Hiding conditions and actions removes their text.
    let bare = SvgOptions { show_conditions: false, show_actions: false, ..SvgOptions::default() };
    let out2 = svg(chart, &sfc_render::layout_with(chart, &bare.layout_options()), &bare);
    assert!(!out2.contains(">Start</text>") && !out2.contains(">Valve</text>"));
    assert!(out2.contains(">Idle</text>"));
}

/// Transition names, when asked for, stand left of their bars and get room there.
#[test]
fn transition_names_get_room() {
    let text = std::fs::read_to_string(crate_dir().join("tests/svg/selection.st")).expect("fixture");
    let chart = &charts("selection.st", &text)[0];
    let opts = SvgOptions { show_transition_names: true, ..SvgOptions::default() };
    let l = sfc_render::layout_with(chart, &opts.layout_options());
    check_layout(chart, &l).unwrap();
    let out = svg(chart, &l, &opts);
    assert!(out.contains("text-anchor=\"end\">TSkip</text>"));
    assert!(l.transitions.iter().all(|t| t.name_rect.is_some()));
}

/// The examples of the repository lay out in the structured form and pass the checks.
#[test]
fn examples_lay_out_structured() {
    for path in st_files(&repo_dir().join("examples")) {
        let text = std::fs::read_to_string(&path).expect("example is UTF-8");
        for chart in charts(&path.display().to_string(), &text) {
            let l = layout(&chart);
            assert_eq!(l.kind, LayoutKind::Structured, "{}: {}", path.display(), chart.pou);
            check_layout(&chart, &l).unwrap_or_else(|e| panic!("{} ({}): {e}", path.display(), chart.pou));
        }
    }
}

/// Every valid fixture of the repository and every simulator semantics fixture lays out, and
/// the layout is complete and correct whatever form it takes.
#[test]
fn repository_fixtures_lay_out() {
    let mut n = 0;
    for dir in ["tests/fixtures/valid", "crates/sfc-sim/tests/semantics"] {
        for path in st_files(&repo_dir().join(dir)) {
            let text = std::fs::read_to_string(&path).expect("fixture is UTF-8");
            let checked = sfc_model::check_source(0, "f.st", &text, &Default::default());
            for chart in &checked.charts {
                let l = layout(chart);
                check_layout(chart, &l).unwrap_or_else(|e| panic!("{} ({}): {e}", path.display(), chart.pou));
                let _ = svg(chart, &l, &SvgOptions::default());
                n += 1;
            }
        }
    }
    assert!(n > 20, "only {n} charts found");
}
