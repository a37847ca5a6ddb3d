//! What `prove` refuses, with a reason and without a panic: profiles it does not model (from
//! the options and from the property file) and a chart that runs itself.

use sfc_prove::{Options, ProveError};

const CHART: &str = "PROGRAM P
    VAR_INPUT
        Go : BOOL;
    END_VAR
    INITIAL_STEP S0: END_STEP
    TRANSITION FROM S0 TO S1 := Go; END_TRANSITION
    STEP S1: END_STEP
    TRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION
END_PROGRAM
";

fn props(text: &str) -> sfc_prove::PropertyFile {
    sfc_prove::props::parse("p.props.toml", text).expect("a property file")
}

#[test]
fn profiles_prove_does_not_model_are_refused() {
    let file = props("[[property]]\nname = \"x\"\nnever = \"S0.X AND S1.X\"\n");
    for p in [sfc_sim::Profile::Matiec, sfc_sim::Profile::Grafcet] {
        let opts = Options { profile: Some(p), ..Default::default() };
        match sfc_prove::prove("p.st", CHART, &file, &opts) {
            Err(ProveError::Unsupported(why)) => assert!(why.contains(p.name()), "{why}"),
            other => panic!("{p:?}: {:?}", other.map(|r| r.properties.len())),
        }
    }
    let file = props("pou = \"P\"\nprofile = \"grafcet\"\n[[property]]\nname = \"x\"\nnever = \"S0.X AND S1.X\"\n");
    match sfc_prove::prove("p.st", CHART, &file, &Options::default()) {
        Err(ProveError::Props(e)) => {
            assert_eq!((e.line, e.column), (2, 11), "{e}");
            assert!(e.message.contains("grafcet profile is not modelled"), "{e}");
        }
        other => panic!("{:?}", other.map(|r| r.properties.len())),
    }
    // `--profile` takes precedence over the file's.
    let opts = Options { profile: Some(sfc_sim::Profile::Codesys), ..Default::default() };
    let r = sfc_prove::prove("p.st", CHART, &file, &opts).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(r.profile, sfc_sim::Profile::Codesys);
    let e = sfc_prove::props::parse("p.props.toml", "profile = \"siemens\"\n").expect_err("unknown profile");
    assert!(e.message.contains("unknown profile `siemens`"), "{e}");
    assert_eq!((e.line, e.column), (1, 11), "{e}");
}

#[test]
fn a_chart_that_runs_itself_is_refused() {
    let chart = "PROGRAM P
    VAR_INPUT
        Go : BOOL;
    END_VAR
    VAR
        N : INT;
    END_VAR
    INITIAL_STEP S0: END_STEP
    TRANSITION FROM S0 TO S1 := Go; END_TRANSITION
    STEP S1: Loop(N); END_STEP
    TRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION
    ACTION Loop:
        INITIAL_STEP L0: Loop(N); END_STEP
        TRANSITION FROM L0 TO L1 := Go; END_TRANSITION
        STEP L1: END_STEP
        TRANSITION FROM L1 TO L0 := TRUE; END_TRANSITION
    END_ACTION
END_PROGRAM
";
    let file = props("[[property]]\nname = \"x\"\nnever = \"S0.X AND S1.X\"\n");
    match sfc_prove::prove("p.st", chart, &file, &Options::default()) {
        Err(ProveError::Props(e)) => assert!(e.message.contains("the chart of action `Loop` runs itself"), "{e}"),
        other => panic!("{:?}", other.map(|r| r.properties.len())),
    }
}
