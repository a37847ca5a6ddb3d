//! Fuzzing the two front ends, the PLCopen XML importer and the IEC text parser and checker,
//! with proptest: real files (the corpus, the examples) mutated at random — bytes flipped,
//! stretches cut, doubled or moved, PLCopen and IEC fragments spliced in — and arbitrary bytes.
//!
//! Each input runs on its own thread with limits: a time limit (a hang, not a speed check: far
//! above what any input needs) and a memory limit enforced by this test binary's allocator.
//! An input that panics, hangs or exceeds the memory limit is written to `tests/fuzz_crashes/`
//! (kept as a regression test: every file there is run by `crash_corpus_stays_fixed`) and fails
//! the test. The CI portion is bounded (`SFC_FUZZ_CASES`, default 64 per front end, a few
//! seconds); set `SFC_FUZZ_CASES=100000` for a full run.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use proptest::prelude::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// Bytes held by allocations of the whole process (the fuzz threads dominate it).
static HELD: AtomicUsize = AtomicUsize::new(0);
/// Per-input memory limit.
const MEMORY_LIMIT: usize = 1 << 30;
/// Per-input time limit: a hang detector.
const TIME_LIMIT: Duration = Duration::from_secs(20);

struct Limited;

// SAFETY: forwards to the system allocator; only counts bytes and refuses past the limit.
unsafe impl GlobalAlloc for Limited {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if HELD.fetch_add(layout.size(), Ordering::Relaxed) + layout.size() > MEMORY_LIMIT {
            HELD.fetch_sub(layout.size(), Ordering::Relaxed);
            return std::ptr::null_mut();
        }
        // SAFETY: same layout contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        HELD.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: `ptr` came from `alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Limited = Limited;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn crash_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_crashes")
}

fn seeds(ext: &str) -> Vec<Vec<u8>> {
    fn walk(d: &Path, ext: &str, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, ext, out);
            } else if p.extension().is_some_and(|x| x == ext) {
                out.push(p);
            }
        }
    }
    let mut paths = Vec::new();
    walk(&root().join("tests/corpus/real"), ext, &mut paths);
    walk(&root().join("examples"), ext, &mut paths);
    walk(&root().join("../shared/corpus"), ext, &mut paths);
    walk(&root().join("tests/fixtures/valid"), ext, &mut paths);
    paths.sort();
    // Small and mid-sized files keep each case fast.
    paths.into_iter().filter_map(|p| std::fs::read(p).ok()).filter(|b| b.len() < 60_000).collect()
}

const XML_SNIPPETS: &[&str] = &[
    "<step localId=\"9999\" name=\"X\" initialStep=\"true\"/>",
    "<transition localId=\"9998\"><connectionPointIn><connection refLocalId=\"9999\"/></connectionPointIn><condition><connection refLocalId=\"9998\"/></condition></transition>",
    "<block localId=\"9997\" typeName=\"AND\"><inputVariables><variable formalParameter=\"IN1\"><connectionPointIn><connection refLocalId=\"9997\"/></connectionPointIn></variable></inputVariables></block>",
    "<jumpStep localId=\"9996\" targetName=\"\"/>",
    "<macroStep localId=\"9995\" name=\"M\"><body><SFC><macroStep localId=\"1\" name=\"M\"/></SFC></body></macroStep>",
    "<![CDATA[ ]]>",
    "&amp;&#x0;&#65;&unknown;",
    "<derived name=\"A.B.C\"/>",
    "<pointer><baseType><pointer/></baseType></pointer>",
    "<vendorElement localId=\"1\"/>",
    "<addData><data name=\"http://www.3s-software.com/plcopenxml/pou\"><pou name=\"Q\" pouType=\"program\"/></data></addData>",
    "\u{feff}",
    "\r\n",
    "<!--",
    "]]>",
];

const ST_SNIPPETS: &[&str] = &[
    "(*",
    "*)",
    "{attribute 'sfc.verbatim' := 'x'}",
    "p^",
    "ADR(x)",
    "INITIAL_STEP",
    "END_STEP",
    "TRANSITION FROM",
    "(((((((((((",
    "T#5d14h",
    "16#FFFF_FFFF_FFFF_FFFF_FF",
    "'$",
    "\u{feff}",
    "\r\n",
    "ACTION",
    "END_PROGRAM",
    "E.V",
];

#[derive(Debug, Clone)]
enum Mutation {
    Flip(usize, u8),
    Cut(usize, usize),
    Double(usize, usize),
    Move(usize, usize, usize),
    Splice(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Mutation::Flip(a, b)),
        (any::<usize>(), 0usize..400).prop_map(|(a, n)| Mutation::Cut(a, n)),
        (any::<usize>(), 0usize..400).prop_map(|(a, n)| Mutation::Double(a, n)),
        (any::<usize>(), 0usize..200, any::<usize>()).prop_map(|(a, n, b)| Mutation::Move(a, n, b)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, k)| Mutation::Splice(a, k)),
    ]
}

fn mutate(mut b: Vec<u8>, ms: &[Mutation], snippets: &[&str]) -> Vec<u8> {
    for m in ms {
        let len = b.len().max(1);
        match *m {
            Mutation::Flip(a, v) => {
                if !b.is_empty() {
                    b[a % len] = v;
                }
            }
            Mutation::Cut(a, n) => {
                let s = a % len;
                let e = (s + n).min(b.len());
                b.drain(s.min(b.len())..e);
            }
            Mutation::Double(a, n) => {
                let s = (a % len).min(b.len());
                let e = (s + n).min(b.len());
                let part = b[s..e].to_vec();
                b.splice(e..e, part);
            }
            Mutation::Move(a, n, to) => {
                let s = (a % len).min(b.len());
                let e = (s + n).min(b.len());
                let part: Vec<u8> = b.drain(s..e).collect();
                let at = to % (b.len() + 1);
                b.splice(at..at, part);
            }
            Mutation::Splice(a, k) => {
                let at = (a % len).min(b.len());
                let s = snippets[k % snippets.len()].as_bytes().to_vec();
                b.splice(at..at, s);
            }
        }
    }
    b
}

/// The work of one input: the front end as `sfc check` runs it (import or parse, then check).
fn front_end(input: &[u8], xml: bool) {
    let text = sfc_syntax::encoding::decode(input).text;
    if xml {
        let (_, checked, _) = sfc_plcopen::check_xml(0, "fuzz.xml", &text, &Default::default());
        if !checked.diagnostics.iter().any(|d| d.code.starts_with("SFC00") || d.code.starts_with("SFC01")) {
            let _ = sfc_plcopen::export(&checked);
        }
    } else {
        let checked = sfc_model::check_source(0, "fuzz.st", &text, &Default::default());
        let _ = sfc_syntax::print::print(&sfc_syntax::parse(0, &text).0);
        let _ = sfc_plcopen::export(&checked);
    }
}

/// Runs one input within the limits; on a panic, a hang or too much memory the input is kept in
/// the crash corpus and the reason returned.
fn run_limited(input: Vec<u8>, xml: bool) -> Result<(), String> {
    let (tx, rx) = std::sync::mpsc::channel();
    let data = input.clone();
    let handle = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(move || {
            let r = std::panic::catch_unwind(|| front_end(&data, xml));
            let _ = tx.send(r.is_ok());
        })
        .map_err(|e| e.to_string())?;
    let outcome = match rx.recv_timeout(TIME_LIMIT) {
        Ok(true) => {
            let _ = handle.join();
            return Ok(());
        }
        Ok(false) => "panicked".to_string(),
        Err(_) => format!("took longer than {TIME_LIMIT:?} (a hang) or ran out of its {MEMORY_LIMIT} bytes"),
    };
    let name = format!("{:016x}.{}", fxhash(&input), if xml { "xml" } else { "st" });
    let _ = std::fs::create_dir_all(crash_dir());
    let _ = std::fs::write(crash_dir().join(&name), &input);
    Err(format!("the input kept as tests/fuzz_crashes/{name} {outcome}"))
}

fn fxhash(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &x| (h ^ x as u64).wrapping_mul(0x100_0000_01b3))
}

fn cases() -> u32 {
    std::env::var("SFC_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn xml_importer_survives_mutated_real_files(k in any::<usize>(), ms in proptest::collection::vec(mutation(), 0..12)) {
        let corpus = seeds("xml");
        prop_assume!(!corpus.is_empty());
        let input = mutate(corpus[k % corpus.len()].clone(), &ms, XML_SNIPPETS);
        if let Err(e) = run_limited(input, true) {
            prop_assert!(false, "{}", e);
        }
    }

    #[test]
    fn text_front_end_survives_mutated_real_files(k in any::<usize>(), ms in proptest::collection::vec(mutation(), 0..12)) {
        let corpus = seeds("st");
        prop_assume!(!corpus.is_empty());
        let input = mutate(corpus[k % corpus.len()].clone(), &ms, ST_SNIPPETS);
        if let Err(e) = run_limited(input, false) {
            prop_assert!(false, "{}", e);
        }
    }

    #[test]
    fn both_front_ends_survive_arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..2000), xml in any::<bool>()) {
        let mut input = bytes;
        if xml {
            input.splice(0..0, b"<project xmlns=\"http://www.plcopen.org/xml/tc6_0201\"><types><pous>".iter().copied());
        }
        if let Err(e) = run_limited(input, xml) {
            prop_assert!(false, "{}", e);
        }
    }
}

/// Every input that once crashed, hung or exhausted memory stays fixed.
#[test]
fn crash_corpus_stays_fixed() {
    let mut failures = Vec::new();
    for e in std::fs::read_dir(crash_dir()).into_iter().flatten().flatten() {
        let p = e.path();
        let xml = p.extension().is_some_and(|x| x == "xml");
        if !(xml || p.extension().is_some_and(|x| x == "st")) {
            continue;
        }
        let input = std::fs::read(&p).expect("crash file");
        if let Err(e) = run_limited(input, xml) {
            failures.push(format!("{}: {e}", p.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
