//! Fuzzing the L5X importer with proptest: the fixtures mutated element by element (lines, since
//! Studio writes one element per line: deleted, doubled, swapped), attribute values replaced
//! (garbage and huge IDs, links that make cycles), bytes flipped and the file truncated. Every
//! input must import without a panic, quickly, and the generated text must check without a
//! panic; malformed XML must give one located SFC0701 error.
//!
//! Each input runs on its own thread with a time limit (a hang detector, far above what any input
//! needs). The CI portion is bounded (`SFC_FUZZ_CASES`, default 64); set `SFC_FUZZ_CASES=20000`
//! for a long run.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

const TIME_LIMIT: Duration = Duration::from_secs(20);

fn seeds() -> Vec<String> {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let mut paths: Vec<PathBuf> = Vec::new();
    for d in [base.clone(), base.join("errors")] {
        for e in std::fs::read_dir(d).into_iter().flatten().flatten() {
            if e.path().extension().is_some_and(|x| x == "L5X") {
                paths.push(e.path());
            }
        }
    }
    paths.sort();
    paths.into_iter().map(|p| std::fs::read_to_string(p).unwrap()).collect()
}

const VALUES: &[&str] = &[
    "",
    "0",
    "-1",
    "99999999999999999999999",
    "18446744073709551615",
    "abc",
    "1e308",
    "NaN",
    "Step_000",
    "&amp;",
    "\u{feff}",
    "Selection",
    "Simultaneous",
    "Diverge",
    "Converge",
    "UserDefined",
    "true",
    "false",
    "SFC_STEP",
    "TIMER",
    "[:=]",
];

const SNIPPETS: &[&str] = &[
    "<DirectedLink FromID=\"0\" ToID=\"0\" Show=\"false\"/>",
    "<DirectedLink FromID=\"1\" ToID=\"0\" Show=\"true\"/>",
    "<DirectedLink FromID=\"0\" ToID=\"999999\" Show=\"true\"/>",
    "<Branch ID=\"0\" Y=\"1\" BranchType=\"Simultaneous\" BranchFlow=\"Converge\"><Leg ID=\"0\"/><Leg ID=\"1\"/></Branch>",
    "<Step ID=\"77\" X=\"1e400\" Y=\"-0\" Operand=\"END_STEP\" InitialStep=\"true\"/>",
    "<Transition ID=\"78\" Operand=\"Tran\"><Condition><STContent><Line Number=\"0\"><![CDATA[Step_000.DN := (((]]></Line></STContent></Condition></Transition>",
    "<Action ID=\"79\" Operand=\"A\" Qualifier=\"Bogus\"><Body><STContent><Line Number=\"0\"><![CDATA[JSR(x); X [:=] Step_001.TMax;]]></Line></STContent></Body></Action>",
    "<Tag Name=\"T\" DataType=\"TIMER\" Dimensions=\"99999999 2 3 4\"/>",
    "<![CDATA[",
    "]]>",
    "<!--",
    "\r\n",
];

#[derive(Debug, Clone)]
enum Mutation {
    DeleteLine(usize),
    DoubleLine(usize),
    SwapLines(usize, usize),
    Value(usize, usize),
    Splice(usize, usize),
    Flip(usize, u8),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::DeleteLine),
        any::<usize>().prop_map(Mutation::DoubleLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::Value(a, b)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::Splice(a, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Mutation::Flip(a, b)),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn mutate(src: &str, ms: &[Mutation]) -> Vec<u8> {
    let mut lines: Vec<String> = src.split('\n').map(str::to_string).collect();
    let mut bytes: Option<Vec<u8>> = None;
    for m in ms {
        let n = lines.len().max(1);
        match *m {
            Mutation::DeleteLine(a) if !lines.is_empty() => {
                lines.remove(a % n);
            }
            Mutation::DoubleLine(a) if !lines.is_empty() => {
                let l = lines[a % n].clone();
                lines.insert(a % n, l);
            }
            Mutation::SwapLines(a, b) if !lines.is_empty() => lines.swap(a % n, b % n),
            Mutation::Value(a, v) if !lines.is_empty() => {
                // The value of the first attribute of the line.
                let l = &mut lines[a % n];
                if let Some(s) = l.find("=\"") {
                    if let Some(e) = l[s + 2..].find('"') {
                        l.replace_range(s + 2..s + 2 + e, VALUES[v % VALUES.len()]);
                    }
                }
            }
            Mutation::Splice(a, k) => lines.insert(a % (lines.len() + 1), SNIPPETS[k % SNIPPETS.len()].to_string()),
            Mutation::Flip(a, v) => {
                let mut b = bytes.take().unwrap_or_else(|| lines.join("\n").into_bytes());
                if !b.is_empty() {
                    let i = a % b.len();
                    b[i] = v;
                }
                lines = String::from_utf8_lossy(&b).split('\n').map(str::to_string).collect();
            }
            Mutation::Truncate(a) => {
                let t = lines.join("\n");
                let mut cut = a % (t.len() + 1);
                while !t.is_char_boundary(cut) {
                    cut -= 1;
                }
                lines = t[..cut].split('\n').map(str::to_string).collect();
            }
            _ => {}
        }
    }
    bytes.unwrap_or_else(|| lines.join("\n").into_bytes())
}

/// What `sfc check` does with the file: import, then check the text.
fn front_end(input: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(input).to_string();
    let out = sfc_l5x::import(0, &text);
    let malformed = roxmltree::Document::parse_with_options(
        &text,
        roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() },
    )
    .is_err();
    if malformed {
        let ok = out.diagnostics.len() == 1
            && out.diagnostics[0].code == "SFC0701"
            && out.diagnostics[0].span.end as usize <= text.len();
        if !ok {
            return Err(format!("malformed XML without one located SFC0701: {:?}", out.diagnostics));
        }
        return Ok(());
    }
    for d in &out.diagnostics {
        if d.span.start > d.span.end || d.span.end as usize > text.len() {
            return Err(format!("a diagnostic outside the file: {d:?}"));
        }
    }
    let checked = sfc_model::check_source(1, "imported", &out.text, &Default::default());
    for d in &checked.diagnostics {
        let r = out.map.to_xml(d.span);
        if r.end as usize > text.len() {
            return Err(format!("a diagnostic of the text maps outside the file: {d:?} → {r:?}"));
        }
    }
    Ok(())
}

fn run_limited(input: Vec<u8>) -> Result<(), String> {
    let (tx, rx) = std::sync::mpsc::channel();
    let handle = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(move || {
            let r = std::panic::catch_unwind(|| front_end(&input));
            let _ = tx.send(r);
        })
        .map_err(|e| e.to_string())?;
    match rx.recv_timeout(TIME_LIMIT) {
        Ok(Ok(r)) => {
            let _ = handle.join();
            r
        }
        Ok(Err(_)) => Err("panic".into()),
        Err(_) => Err(format!("no answer within {TIME_LIMIT:?}")),
    }
}

fn cases() -> u32 {
    std::env::var("SFC_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_fixtures_import_without_panic(seed in any::<usize>(), ms in prop::collection::vec(mutation(), 1..6)) {
        let seeds = seeds();
        let src = &seeds[seed % seeds.len()];
        let input = mutate(src, &ms);
        let r = run_limited(input.clone());
        prop_assert!(r.is_ok(), "{:?} on:\n{}", r, String::from_utf8_lossy(&input));
    }
}

#[test]
fn hostile_inputs_do_not_panic() {
    let big = format!(
        "<RSLogix5000Content><Controller><Programs><Program Name=\"P\"><Routines><Routine Name=\"R\" Type=\"SFC\"><SFCContent>{}{}</SFCContent></Routine></Routines></Program></Programs></Controller></RSLogix5000Content>",
        (0..2000).map(|i| format!("<Branch ID=\"{i}\" Y=\"0\" BranchType=\"Simultaneous\" BranchFlow=\"Converge\"><Leg ID=\"{}\"/></Branch>", i + 100_000)).collect::<String>(),
        (0..2000).map(|i| format!("<DirectedLink FromID=\"{}\" ToID=\"{}\"/>", i, (i + 1) % 2000)).collect::<String>(),
    );
    // Every transition's walk goes through one convergence of 2000 legs: the walks share one
    // budget, so this stays fast.
    let n = 2000;
    let wide = format!(
        "<RSLogix5000Content><Controller><Programs><Program Name=\"P\"><Routines><Routine Name=\"R\" Type=\"SFC\"><SFCContent><Step ID=\"0\" Operand=\"S\" InitialStep=\"true\"/>{}<Branch ID=\"1\" Y=\"0\" BranchType=\"Simultaneous\" BranchFlow=\"Converge\">{}</Branch>{}</SFCContent></Routine></Routines></Program></Programs></Controller></RSLogix5000Content>",
        (0..n).map(|i| format!("<Transition ID=\"{}\" Operand=\"T{i}\"/>", 10 + i)).collect::<String>(),
        (0..n).map(|i| format!("<Leg ID=\"{}\"/>", 100_000 + i)).collect::<String>(),
        (0..n).map(|i| format!("<DirectedLink FromID=\"1\" ToID=\"{}\"/><DirectedLink FromID=\"{}\" ToID=\"{}\"/>", 10 + i, 10 + i, 100_000 + i)).collect::<String>(),
    );
    let started = std::time::Instant::now();
    assert!(run_limited(wide.into_bytes()).is_ok());
    assert!(started.elapsed() < Duration::from_secs(10), "{:?}", started.elapsed());
    let inputs = [
        "",
        "<",
        "<RSLogix5000Content/>",
        "<RSLogix5000Content><Controller/></RSLogix5000Content>",
        "<RSLogix5000Content><Controller><Programs><Program><Routines><Routine Type=\"SFC\"/></Routines></Program></Programs></Controller></RSLogix5000Content>",
        "<RSLogix5000Content><Controller><Programs><Program><Routines><Routine Type=\"SFC\"><SFCContent><Step ID=\"0\"/><Step ID=\"0\"/><Transition ID=\"1\"/><DirectedLink FromID=\"1\" ToID=\"1\"/></SFCContent></Routine></Routines></Program></Programs></Controller></RSLogix5000Content>",
        big.as_str(),
    ];
    for i in inputs {
        let r = run_limited(i.as_bytes().to_vec());
        assert!(r.is_ok(), "{r:?} on {}", &i[..i.len().min(200)]);
    }
}
