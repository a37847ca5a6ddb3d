//! `sfc prove` as a user runs it: the property file found beside the chart, exit codes 0 / 1 / 2,
//! `--format json`, the witness scenario written beside the chart (or into `--witness-dir`),
//! and `sfc test` on that witness failing on the property itself.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../sfc-prove/tests/fixtures")
}

fn sfc_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).current_dir(dir).output().expect("sfc runs")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// A scratch directory holding copies of the fixture charts `names` with their property files.
fn scratch(test: &str, names: &[&str]) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-prove-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    for n in names {
        for ext in ["st", "props.toml"] {
            std::fs::copy(fixtures().join(format!("{n}.{ext}")), d.join(format!("{n}.{ext}"))).unwrap();
        }
    }
    d
}

#[test]
fn all_properties_hold_exits_0() {
    let d = scratch("holds", &["st_enum_case"]);
    let o = sfc_in(&d, &["prove", "st_enum_case.st"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("HOLDS    power follows the previous mode"), "{out}");
    assert!(out.contains("3 held, 0 violated, 0 unknown"), "{out}");
    // Nothing violated, nothing written.
    let written: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".witness.toml"))
        .collect();
    assert!(written.is_empty(), "{written:?}");
}

#[test]
fn violation_exits_1_and_its_witness_fails_sfc_test_on_the_property() {
    let d = scratch("violated", &["carwash"]);
    let o = sfc_in(&d, &["prove", "carwash.st"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("VIOLATED no travel without a car"), "{out}");
    assert!(out.contains("replayed in the simulator"), "{out}");
    let witness = d.join("carwash.no-travel-without-a-car.witness.toml");
    let scenario = std::fs::read_to_string(&witness).unwrap_or_else(|e| panic!("{}: {e}\n{out}", witness.display()));
    // The property is stated in the scenario with an interval expectation.
    assert!(scenario.contains("never = \"Travel AND NOT CarPresent\""), "{scenario}");
    let t = sfc_in(&d, &["test", "carwash.no-travel-without-a-car.witness.toml"]);
    let tout = text(&t);
    assert_eq!(t.status.code(), Some(1), "{tout}");
    assert!(tout.contains("never from T#0s to"), "{tout}");
    assert!(tout.contains("`Travel AND NOT CarPresent` is TRUE"), "{tout}");
}

#[test]
fn response_witness_fails_on_its_deadline() {
    let d = scratch("response", &["blinker"]);
    let w = d.join("witnesses");
    let o = sfc_in(&d, &["prove", "blinker.st", "--witness-dir", "witnesses"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    let file = w.join("blinker.on-within-10-ms-of-start.witness.toml");
    let scenario = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}\n{out}", file.display()));
    assert!(scenario.contains("after = \"Start AND S1.X\""), "{scenario}");
    assert!(scenario.contains("within = \"T#20ms\""), "{scenario}");
    // The witness names the chart relative to where it is written.
    assert!(scenario.contains("chart = \"../blinker.st\""), "{scenario}");
    let t = sfc_in(&w, &["test", "blinker.on-within-10-ms-of-start.witness.toml"]);
    let tout = text(&t);
    assert_eq!(t.status.code(), Some(1), "{tout}");
    assert!(tout.contains("within T#20ms after"), "{tout}");
}

#[test]
fn json_lists_the_verdicts() {
    let d = scratch("json", &["carwash"]);
    let o = sfc_in(&d, &["prove", "carwash.st", "--format", "json", "--no-witness"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    let props = v["properties"].as_array().expect("properties");
    let verdict =
        |name: &str| props.iter().find(|p| p["name"] == name).map(|p| p["verdict"].as_str().unwrap_or("").to_string());
    assert_eq!(verdict("never forward and back").as_deref(), Some("holds"), "{v}");
    assert_eq!(verdict("no travel without a car").as_deref(), Some("violated"), "{v}");
    assert_eq!(v["summary"]["violated"], 1, "{v}");
    let holds = props.iter().find(|p| p["name"] == "never forward and back").unwrap();
    assert!(holds["method"].as_str().is_some_and(|m| !m.is_empty()), "{holds}");
    // --no-witness writes nothing.
    assert!(!d.join("carwash.no-travel-without-a-car.witness.toml").exists());
}

#[test]
fn usage_and_input_errors_exit_2() {
    let d = scratch("usage", &["carwash"]);
    // No property file beside the chart.
    std::fs::copy(d.join("carwash.st"), d.join("alone.st")).unwrap();
    let o = sfc_in(&d, &["prove", "alone.st"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("alone.props.toml"), "{}", text(&o));
    // A property file with an error, located at its line and column.
    std::fs::write(d.join("bad.props.toml"), "[[property]]\nname = \"x\"\nalways = \"Travel AND Nonsense\"\n").unwrap();
    let o = sfc_in(&d, &["prove", "carwash.st", "--properties", "bad.props.toml"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(2), "{out}");
    assert!(out.contains("bad.props.toml:3:"), "{out}");
    assert!(out.contains("Nonsense"), "{out}");
    // A chart that does not exist, and an unknown option.
    assert_eq!(sfc_in(&d, &["prove", "missing.st"]).status.code(), Some(2));
    assert_eq!(sfc_in(&d, &["prove", "carwash.st", "--frobnicate"]).status.code(), Some(2));
}

/// Induction starts only from states a run can have: before scan 0 every variable holds its
/// initial value. Without that, a counter off its initial value before scan 0 (−9, which no run
/// has) made "Rejects <= Parts" fail induction, and the search for the reachable set ran out of
/// its budget on the 200-step version of this chart.
#[test]
fn a_counter_invariant_is_proved_by_induction() {
    let d = scratch("gate", &["counter_gate"]);
    let o = sfc_in(&d, &["prove", "counter_gate.st"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("HOLDS    no more rejects than parts\n    method: 1-induction"), "{out}");
    assert!(out.contains("2 held, 0 violated, 0 unknown"), "{out}");
}

/// `--profile codesys`: the chart is proved under CODESYS's scan (actions before the
/// evolution, no priorities); the witness says `profile = "codesys"`, so `sfc test` replays it
/// under that profile and fails on the property. The same chart holds under `iec`.
#[test]
fn codesys_profile_is_proved_and_its_witness_replays_under_codesys() {
    let d = scratch("codesys", &["codesys_priority"]);
    let o = sfc_in(&d, &["prove", "codesys_priority.st"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("profile iec"), "{out}");
    let o = sfc_in(&d, &["prove", "codesys_priority.st", "--profile", "codesys"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("profile codesys"), "{out}");
    assert!(out.contains("VIOLATED left is never taken"), "{out}");
    assert!(out.contains("VIOLATED motor follows its step"), "{out}");
    assert!(out.contains("HOLDS    motor within a scan of its step"), "{out}");
    assert!(!out.contains("NOT reproduced"), "{out}");
    let file = "codesys_priority.left-is-never-taken.witness.toml";
    let scenario = std::fs::read_to_string(d.join(file)).unwrap_or_else(|e| panic!("{file}: {e}\n{out}"));
    assert!(scenario.contains("profile = \"codesys\""), "{scenario}");
    let t = sfc_in(&d, &["test", file]);
    let tout = text(&t);
    assert_eq!(t.status.code(), Some(1), "{tout}");
    assert!(tout.contains("`GoLeft.X` is TRUE"), "{tout}");
    // Under iec the same inputs take the right branch: the witness passes.
    let iec = scenario.replace("profile = \"codesys\"\n", "");
    std::fs::write(d.join("iec.witness.toml"), iec).unwrap();
    let t = sfc_in(&d, &["test", "iec.witness.toml"]);
    assert_eq!(t.status.code(), Some(0), "{}", text(&t));
}

/// The property file may name the profile; `--profile` takes precedence. Profiles `prove`
/// does not model are refused (exit 2), on the command line and in the file.
#[test]
fn the_property_file_names_the_profile() {
    let d = scratch("profile-file", &["codesys_priority"]);
    let props = std::fs::read_to_string(d.join("codesys_priority.props.toml")).unwrap();
    std::fs::write(d.join("codesys_priority.props.toml"), format!("profile = \"codesys\"\n{props}")).unwrap();
    let o = sfc_in(&d, &["prove", "codesys_priority.st", "--format", "json", "--no-witness"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    assert_eq!(v["profile"], "codesys", "{v}");
    let o = sfc_in(&d, &["prove", "codesys_priority.st", "--profile", "iec"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let o = sfc_in(&d, &["prove", "codesys_priority.st", "--profile", "matiec"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(2), "{out}");
    assert!(out.contains("matiec profile is not modelled"), "{out}");
    std::fs::write(d.join("g.props.toml"), format!("profile = \"grafcet\"\n{props}")).unwrap();
    let o = sfc_in(&d, &["prove", "codesys_priority.st", "--properties", "g.props.toml"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(2), "{out}");
    assert!(out.contains("g.props.toml:1:"), "{out}");
    assert!(out.contains("grafcet profile is not modelled"), "{out}");
}

/// Step actions and actions written in SFC are modelled: a function block's SFC action run by
/// `Cyl.ACT_Extend(SFCReset := Abort)`, its steps read through the instance (`Cyl.Extend.X`);
/// step actions (entry, step, exit) around an IEC action. Each violation's witness replays in
/// `sfc test` under the profile it was found under.
#[test]
fn step_actions_and_sfc_actions_are_proved_under_both_profiles() {
    let d = scratch("sfc-actions", &["sfc_action_fb", "step_actions"]);
    for profile in ["iec", "codesys"] {
        let w = format!("w-{profile}");
        let o = sfc_in(&d, &["prove", "sfc_action_fb.st", "--profile", profile, "--witness-dir", &w]);
        let out = text(&o);
        assert_eq!(o.status.code(), Some(1), "{out}");
        assert!(out.contains("HOLDS    one step of the action at a time"), "{out}");
        // Under codesys a call with SFCReset goes on processing the initial situation, whose
        // transitions are tested in that same call (docs/sim.md, "The `codesys` profile").
        if profile == "iec" {
            assert!(out.contains("HOLDS    abort puts the action back"), "{out}");
        } else {
            assert!(out.contains("VIOLATED abort puts the action back"), "{out}");
        }
        assert!(out.contains("VIOLATED the valve follows the step"), "{out}");
        assert!(!out.contains("NOT reproduced"), "{out}");
        // No statement or step action left out of the model.
        assert!(!out.contains("at line"), "{out}");
        let t = sfc_in(&d.join(&w), &["test", "sfc_action_fb.the-valve-follows-the-step.witness.toml"]);
        let tout = text(&t);
        assert_eq!(t.status.code(), Some(1), "{tout}");
        assert!(tout.contains("`Out = Cyl.Extend.X` is FALSE"), "{tout}");
        let o = sfc_in(&d, &["prove", "step_actions.st", "--profile", profile, "--witness-dir", &w]);
        let out = text(&o);
        assert_eq!(o.status.code(), Some(1), "{out}");
        let follows =
            if profile == "iec" { "HOLDS    in fill follows the step" } else { "VIOLATED in fill follows the step" };
        assert!(out.contains(follows), "{out}");
        assert!(out.contains("HOLDS    step actions before the IEC actions"), "{out}");
        assert!(!out.contains("NOT reproduced"), "{out}");
        let t = sfc_in(&d.join(&w), &["test", "step_actions.the-pump-runs-only-in-drain.witness.toml"]);
        assert_eq!(t.status.code(), Some(1), "{}", text(&t));
    }
}

/// The machine project in the shape of a CODESYS export (the bottling line: eleven function
/// blocks whose SFC actions call each other's actions, with step actions): `sfc prove` takes
/// the XML itself, chooses `codesys` from its vendor (said in a note), decides every property of
/// `bottling_line.props.toml` (mutual exclusion of modes and of two actuators, modes reachable,
/// responses within a time), and each violation's witness replays in `sfc test`, failing on the
/// property.
#[test]
fn the_bottling_line_export_is_proved_under_codesys() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/real/codesys");
    let d = std::env::temp_dir().join(format!("sfc-prove-bottling-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    for f in ["bottling_line_eleven_blocks.xml", "bottling_line.props.toml"] {
        std::fs::copy(src.join(f), d.join(f)).unwrap();
    }
    let o = sfc_in(&d, &["prove", "bottling_line_eleven_blocks.xml", "--properties", "bottling_line.props.toml"]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(
        out.contains("note: proved with profile codesys: bottling_line_eleven_blocks.xml is a CODESYS export"),
        "{out}"
    );
    assert!(out.contains("4 held, 3 violated, 0 unknown"), "{out}");
    for held in [
        "production and stopping exclude each other",
        "init and production exclude each other",
        "the line can be stopped",
        "rinsing and capping run in parallel",
    ] {
        assert!(out.contains(&format!("HOLDS    {held}")), "{held}\n{out}");
    }
    let witnesses = [
        "the-conveyor-drive-and-the-capping-head-are-never-on-together",
        "a-stop-is-answered-within-10-ms",
        "the-run-lamp-is-off-while-stopping",
    ];
    for w in witnesses {
        let file = format!("bottling_line_eleven_blocks.{w}.witness.toml");
        assert!(d.join(&file).exists(), "{file}\n{out}");
        let t = sfc_in(&d, &["test", &file]);
        let tout = text(&t);
        assert_eq!(t.status.code(), Some(1), "the witness fails on its property: {tout}");
        assert!(tout.contains("0 passed, 1 failed"), "{tout}");
    }
    assert!(!out.contains("NOT reproduced"), "{out}");
}
