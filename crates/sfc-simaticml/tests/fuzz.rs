//! Fuzzing the SimaticML importer with proptest: the fixtures mutated at random — lines
//! deleted, doubled and moved (whole elements, since the exports write one element a line),
//! UIds and numbers replaced (dangling references), the power rail replaced by a part's output
//! (wire cycles), huge `Cardinality` and `Number` values, GRAPH snippets spliced in, the file
//! truncated. Each input runs on its own thread under a time limit: the importer must never
//! panic nor hang; malformed XML must give the located SFC0701 and nothing else; every
//! diagnostic must lie inside the file. The CI portion is bounded (`SFC_FUZZ_CASES`, default
//! 64); `SFC_FUZZ_CASES=20000` for a long run.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;
use proptest::prelude::*;
use std::time::Duration;

const TIME_LIMIT: Duration = Duration::from_secs(20);

fn seeds() -> Vec<String> {
    common::fixtures().iter().map(|p| std::fs::read_to_string(p).unwrap()).collect()
}

const SNIPPETS: &[&str] = &[
    "<Part Name=\"O\" UId=\"21\"><TemplateValue Name=\"Card\" Type=\"Cardinality\">4294967295</TemplateValue></Part>",
    "<Wire UId=\"99\"><NameCon UId=\"21\" Name=\"out\" /><NameCon UId=\"21\" Name=\"in\" /></Wire>",
    "<Wire UId=\"98\"><Powerrail /><IdentCon UId=\"21\" /><NameCon UId=\"999\" Name=\"in1\" /></Wire>",
    "<Branch Number=\"1\" Type=\"AltBegin\" Cardinality=\"99999999999\" />",
    "<Connection><NodeFrom><BranchRef Number=\"1\" Out=\"0\" /></NodeFrom><NodeTo><BranchRef Number=\"1\" In=\"0\" /></NodeTo><LinkType>Jump</LinkType></Connection>",
    "<Connection><NodeFrom><TransitionRef Number=\"1\" /></NodeFrom><NodeTo><TransitionRef Number=\"1\" /></NodeTo><LinkType>Direct</LinkType></Connection>",
    "<Step Number=\"1\" Init=\"true\" Name=\"\" />",
    "<Transition Number=\"-5\" Name=\"T#5S\" />",
    "<Action Qualifier=\"D\" Event=\"S1\"><Token Text=\"&quot;A\" /></Action>",
    "<Action Qualifier=\"CS\"><Token Text=\"#x , \" /><Token Text=\"[\" /></Action>",
    "<Access Scope=\"Address\" UId=\"21\"><Address Area=\"Input\" /></Access>",
    "<Sequence><Steps /><Transitions /><Branches /><Connections /></Sequence>",
    "<Member Name=\"x\" Datatype=\"Array[0..3] of Struct\" />",
    "&#xD800;",
    "<![CDATA[",
];

#[derive(Debug, Clone)]
enum Mutation {
    DeleteLine(usize),
    DoubleLine(usize),
    MoveLine(usize, usize),
    Renumber(usize, u32),
    RailToOut(usize),
    Splice(usize, usize),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::DeleteLine),
        any::<usize>().prop_map(Mutation::DoubleLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::MoveLine(a, b)),
        (any::<usize>(), prop_oneof![Just(0u32), Just(1), Just(21), Just(u32::MAX), 0u32..100])
            .prop_map(|(a, n)| Mutation::Renumber(a, n)),
        any::<usize>().prop_map(Mutation::RailToOut),
        (any::<usize>(), any::<usize>()).prop_map(|(a, k)| Mutation::Splice(a, k)),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn mutate(src: &str, ms: &[Mutation]) -> String {
    let mut lines: Vec<String> = src.lines().map(str::to_string).collect();
    for m in ms {
        let n = lines.len().max(1);
        match *m {
            Mutation::DeleteLine(a) => {
                if !lines.is_empty() {
                    lines.remove(a % n);
                }
            }
            Mutation::DoubleLine(a) => {
                if let Some(l) = lines.get(a % n).cloned() {
                    lines.insert(a % n, l);
                }
            }
            Mutation::MoveLine(a, b) => {
                if !lines.is_empty() {
                    let l = lines.remove(a % n);
                    let to = b % (lines.len() + 1);
                    lines.insert(to, l);
                }
            }
            Mutation::Renumber(a, v) => {
                // Replace the value of one `UId="…"` or `Number="…"` attribute.
                let hits: Vec<usize> = lines
                    .iter()
                    .enumerate()
                    .filter(|(_, l)| l.contains("UId=\"") || l.contains("Number=\""))
                    .map(|(i, _)| i)
                    .collect();
                if let Some(&i) = hits.get(a % hits.len().max(1)) {
                    let l = &lines[i];
                    let key = if l.contains("UId=\"") { "UId=\"" } else { "Number=\"" };
                    let s = l.find(key).unwrap() + key.len();
                    let e = s + l[s..].find('"').unwrap_or(0);
                    lines[i] = format!("{}{v}{}", &l[..s], &l[e..]);
                }
            }
            Mutation::RailToOut(a) => {
                let hits: Vec<usize> =
                    lines.iter().enumerate().filter(|(_, l)| l.contains("<Powerrail />")).map(|(i, _)| i).collect();
                if let Some(&i) = hits.get(a % hits.len().max(1)) {
                    lines[i] = lines[i].replace("<Powerrail />", "<NameCon UId=\"22\" Name=\"out\" />");
                }
            }
            Mutation::Splice(a, k) => {
                let at = a % (lines.len() + 1);
                lines.insert(at, SNIPPETS[k % SNIPPETS.len()].to_string());
            }
            Mutation::Truncate(a) => {
                let text = lines.join("\n");
                let mut cut = a % (text.len() + 1);
                while !text.is_char_boundary(cut) {
                    cut -= 1;
                }
                lines = text[..cut].lines().map(str::to_string).collect();
            }
        }
    }
    lines.join("\n")
}

fn run_limited(input: String) -> Result<(), String> {
    let (tx, rx) = std::sync::mpsc::channel();
    let data = input.clone();
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(move || {
            let r = std::panic::catch_unwind(|| {
                let out = sfc_simaticml::import(0, &data);
                let _ = sfc_syntax::parse(0, &out.text);
                out.diagnostics
            });
            let _ = tx.send(r);
        })
        .map_err(|e| e.to_string())?;
    match rx.recv_timeout(TIME_LIMIT) {
        Ok(Ok(diags)) => {
            for d in &diags {
                if d.span.start > d.span.end || d.span.end as usize > input.len() {
                    return Err(format!("diagnostic outside the file: {d:?}"));
                }
            }
            let well_formed = roxmltree::Document::parse_with_options(
                &input,
                roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() },
            )
            .is_ok();
            let one_located_error = diags.len() == 1 && diags[0].code == "SFC0701";
            if !well_formed && !one_located_error {
                return Err(format!("malformed XML without one SFC0701: {diags:?}"));
            }
            Ok(())
        }
        Ok(Err(_)) => Err("panic".into()),
        Err(_) => Err("hang (time limit)".into()),
    }
}

fn cases() -> u32 {
    std::env::var("SFC_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn mutated_exports_never_panic_nor_hang(seed in any::<usize>(), ms in proptest::collection::vec(mutation(), 1..8)) {
        let seeds = seeds();
        let src = &seeds[seed % seeds.len()];
        let input = mutate(src, &ms);
        if let Err(e) = run_limited(input.clone()) {
            let dir = std::env::temp_dir().join("sfc-simaticml-fuzz");
            let _ = std::fs::create_dir_all(&dir);
            let file = dir.join(format!("crash-{}.xml", seed));
            let _ = std::fs::write(&file, &input);
            prop_assert!(false, "{e} (input kept in {})", file.display());
        }
    }
}

#[test]
fn hostile_inputs_do_not_panic() {
    let deep = format!(
        "<Document><Engineering/>{}{}</Document>",
        "<SW.Blocks.FB>".repeat(3000),
        "</SW.Blocks.FB>".repeat(3000)
    );
    let wide_or = {
        let mut s = String::from("<Document><Engineering version=\"V20\"/><SW.Blocks.FB><AttributeList><Name>X</Name><ProgrammingLanguage>GRAPH</ProgrammingLanguage></AttributeList><ObjectList><SW.Blocks.CompileUnit><AttributeList><NetworkSource><Graph xmlns=\"http://www.siemens.com/automation/Openness/SW/NetworkSource/Graph/v5\"><Sequence><Steps><Step Number=\"1\" Init=\"true\" Name=\"A\"/></Steps><Transitions><Transition Number=\"1\" Name=\"T\"><FlgNet><Parts>");
        // A ladder of 200 O boxes each fed twice by the previous one: an exponential expression.
        for i in 0..200 {
            s.push_str(&format!("<Part Name=\"O\" UId=\"{}\"/>", 100 + i));
        }
        s.push_str("<Part Name=\"TrCoil\" UId=\"1\"/></Parts><Wires><Wire><Powerrail/><NameCon UId=\"100\" Name=\"in1\"/><NameCon UId=\"100\" Name=\"in2\"/></Wire>");
        for i in 1..200 {
            s.push_str(&format!("<Wire><NameCon UId=\"{}\" Name=\"out\"/><NameCon UId=\"{}\" Name=\"in1\"/><NameCon UId=\"{}\" Name=\"in2\"/></Wire>", 99 + i, 100 + i, 100 + i));
        }
        s.push_str("<Wire><NameCon UId=\"299\" Name=\"out\"/><NameCon UId=\"1\" Name=\"in\"/></Wire></Wires></FlgNet></Transition></Transitions><Branches/><Connections><Connection><NodeFrom><StepRef Number=\"1\"/></NodeFrom><NodeTo><TransitionRef Number=\"1\"/></NodeTo><LinkType>Direct</LinkType></Connection><Connection><NodeFrom><TransitionRef Number=\"1\"/></NodeFrom><NodeTo><StepRef Number=\"1\"/></NodeTo><LinkType>Jump</LinkType></Connection></Connections></Sequence></Graph></NetworkSource></AttributeList></SW.Blocks.CompileUnit></ObjectList></SW.Blocks.FB></Document>");
        s
    };
    for x in [
        "",
        "<",
        "<Document",
        "<Document/>",
        "<Document><Engineering/></Document>",
        "\u{feff}<Document><DocumentInfo/><SW.Blocks.FB/></Document>",
        deep.as_str(),
        wide_or.as_str(),
    ] {
        run_limited(x.to_string()).unwrap_or_else(|e| panic!("{e}: {}", &x[..x.len().min(200)]));
    }
}
