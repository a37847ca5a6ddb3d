//! `cargo bench -p sfc-cli --bench codesys`: `sfc check` (with analysis) of a CODESYS project
//! export of about 2 MB, run as users run it (the `sfc` binary), printing the figure.
//!
//! The project is written in the shapes CODESYS V3.5 exports (POUs in the application's resource
//! `addData`, every position (0, 0), `sfc/element` properties on every SFC element): 59 function
//! blocks whose body is ST, each with documented variables, three ST actions and one action
//! written in SFC (8 steps, guards with expressions over inputs, step times and outputs, IEC
//! associations and step actions), and a program whose chart calls them: 60 SFC bodies of about
//! 500 steps in all. Issue 31's target: under 1 s on the 2-core machine.
//!
//! Under `cargo test` (no `--bench` argument) a project of 3 blocks is checked once as a smoke
//! test.

use std::fmt::Write as _;
use std::process::Command;
use std::time::Instant;

const SFC: &str = env!("CARGO_BIN_EXE_sfc");

fn element(name: &str, initial: Option<bool>, extra: &str) -> String {
    let init = match initial {
        Some(i) => format!(
            "\n                  <attribute guid=\"6844a48e-46c2-4cc8-a185-a478f3b99cc0\">{}</attribute>",
            if i { "TRUE" } else { "FALSE" }
        ),
        None => String::new(),
    };
    format!(
        r#"
              <addData>
                <data name="http://www.3s-software.com/plcopenxml/sfc/element" handleUnknown="implementation">
                  <attributes xmlns="">
                  <attribute guid="38391c6d-6d4a-42f8-8ee7-9f45e5adafa8">{name}</attribute>
                  <attribute guid="01580b27-6378-448b-8ecb-0e4b795b58d6">FALSE</attribute>
                  <attribute guid="bc882c11-1e91-4dd8-a6b8-2075724ed18b">0</attribute>{init}{extra}
                  </attributes>
                </data>
              </addData>"#
    )
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A loop of `n` steps: step `k` sets output `k % 4`, its guard reads inputs, step time and an
/// output; entry and exit actions on every other step.
fn chart(prefix: &str, n: usize) -> String {
    let mut s = String::new();
    let mut id = 0;
    let mut prev: Option<usize> = None;
    for k in 0..n {
        let step = id;
        id += 1;
        let name = format!("{prefix}_S{k}");
        let input = match prev {
            None => "<connectionPointIn />".to_string(),
            Some(t) => format!("<connectionPointIn><connection refLocalId=\"{t}\" /></connectionPointIn>"),
        };
        let extra = if k % 2 == 1 {
            "\n                  <attribute guid=\"a6b08bd8-b696-47e3-9cbf-7408b61c9ff8\">Act_Log</attribute>\n                  <attribute guid=\"a2621e18-7de3-4ea6-ae6d-89e9e0b7befd\">Act_Clear</attribute>"
        } else {
            ""
        };
        let _ = write!(
            s,
            r#"
            <step localId="{step}" initialStep="{}" name="{name}">
              <position x="0" y="0" />
              {input}
              <connectionPointOut formalParameter="sfc" />
              <connectionPointOutAction formalParameter="x" />{}
            </step>"#,
            k == 0,
            element(&name, Some(k == 0), extra)
        );
        let block = id;
        let act = id + 1;
        id += 2;
        let _ = write!(
            s,
            r#"
            <actionBlock localId="{block}">
              <position x="0" y="0" />
              <connectionPointIn><connection refLocalId="{step}" /></connectionPointIn>
              <action localId="{act}" qualifier="N" duration="" indicator="">
                <relPosition x="0" y="0" />
                <reference name="Out{}" />
                <connectionPointOut />
              </action>
            </actionBlock>"#,
            k % 4
        );
        let guard = format!(
            "(In{} AND NOT In{}) OR ({name}.t >= T#{}MS AND Level > {}) OR Out{} AND Count < {}",
            k % 6,
            (k + 1) % 6,
            100 + 10 * k,
            k * 5,
            (k + 2) % 4,
            k + 3
        );
        let var = id;
        let tr = id + 1;
        id += 2;
        let _ = write!(
            s,
            r#"
            <inVariable localId="{var}">
              <position x="0" y="0" />
              <connectionPointOut />
              <expression>{g}</expression>
            </inVariable>
            <transition localId="{tr}">
              <position x="0" y="0" />
              <connectionPointIn><connection refLocalId="{step}" formalParameter="sfc" /></connectionPointIn>
              <condition><connectionPointIn><connection refLocalId="{var}" /></connectionPointIn></condition>{}
            </transition>"#,
            element(
                &xml_escape(&guard),
                None,
                "\n                  <attribute guid=\"8294df19-5962-4dee-a874-1051dabb0e3e\">0</attribute>"
            ),
            g = xml_escape(&guard)
        );
        prev = Some(tr);
    }
    let _ = write!(
        s,
        r#"
            <jumpStep localId="{id}" targetName="{prefix}_S0">
              <position x="0" y="0" />
              <connectionPointIn><connection refLocalId="{}" /></connectionPointIn>{}
            </jumpStep>"#,
        prev.unwrap_or(0),
        element(&format!("{prefix}_S0"), None, "")
    );
    s
}

fn var(name: &str, ty: &str, doc: &str) -> String {
    format!(
        r#"
              <variable name="{name}">
                <type><{ty} /></type>
                <documentation><xhtml xmlns="http://www.w3.org/1999/xhtml">{doc}</xhtml></documentation>
              </variable>"#
    )
}

fn st_action(name: &str, body: &str) -> String {
    format!(
        r#"
            <action name="{name}">
              <body><ST><xhtml xmlns="http://www.w3.org/1999/xhtml">{}</xhtml></ST></body>
              <addData>
                <data name="http://www.3s-software.com/plcopenxml/objectid" handleUnknown="discard">
                  <ObjectId>00000000-0000-4000-8000-{:012x}</ObjectId>
                </data>
              </addData>
            </action>"#,
        xml_escape(body),
        name.len()
    )
}

fn block(k: usize, steps: usize) -> String {
    let mut inputs = String::new();
    for i in 0..6 {
        inputs.push_str(&var(
            &format!("In{i}"),
            "BOOL",
            &format!("Sensor {i} of station {k}: TRUE while the part is in front of it"),
        ));
    }
    inputs.push_str(&var("Level", "INT", "Filling level in percent, from the analogue card"));
    let mut outputs = String::new();
    for i in 0..4 {
        outputs.push_str(&var(&format!("Out{i}"), "BOOL", &format!("Valve {i}: the coil is driven while TRUE")));
    }
    let mut locals = var("Count", "INT", "Parts handled since the last reset");
    locals.push_str(&var("Log", "INT", "Steps entered, for the operator's statistics"));
    for i in 0..12 {
        locals.push_str(&var(&format!("Spare{i}"), "DINT", "Reserved for the next revision of the station"));
    }
    let mut body = String::new();
    for i in 0..12 {
        let _ = writeln!(body, "IF In{} AND Level > {} THEN\n    Count := Count + 1;\nELSIF NOT In{} THEN\n    Spare{} := Spare{} + {};\nEND_IF;", i % 6, i * 7, (i + 3) % 6, i % 6, i % 6, i + 1);
    }
    let prefix = format!("B{k}");
    format!(
        r#"
      <data name="http://www.3s-software.com/plcopenxml/pou" handleUnknown="implementation">
        <pou name="Station{k}" pouType="functionBlock">
          <interface>
            <inputVars>{inputs}
            </inputVars>
            <outputVars>{outputs}
            </outputVars>
            <localVars>{locals}
            </localVars>
          </interface>
          <actions>{}{}{}
            <action name="Act_Sequence">
              <body>
                <SFC>{}
                </SFC>
              </body>
            </action>
          </actions>
          <body><ST><xhtml xmlns="http://www.w3.org/1999/xhtml">{}</xhtml></ST></body>
        </pou>
      </data>"#,
        st_action("Act_Log", "Log := Log + 1;"),
        st_action("Act_Clear", "Out0 := FALSE;\nOut1 := FALSE;\nOut2 := FALSE;\nOut3 := FALSE;"),
        st_action("Act_Reset", &body),
        chart(&prefix, steps),
        xml_escape(&body)
    )
}

/// The project: `blocks` stations and MAIN, each chart of `steps` steps.
fn project(blocks: usize, steps: usize) -> String {
    let mut pous = String::new();
    for k in 0..blocks {
        pous.push_str(&block(k, steps));
    }
    let mut vars = String::new();
    let mut calls = String::new();
    for k in 0..blocks {
        let _ = write!(
            vars,
            "\n              <variable name=\"St{k}\"><type><derived name=\"Station{k}\" /></type></variable>"
        );
        let _ = writeln!(calls, "St{k}(In0 := Run, Level := 50);\nSt{k}.Act_Sequence();");
    }
    let main_chart = {
        let mut c = chart("M", steps.max(4) + 4);
        // Every step runs the stations (N); the guards still read the outputs.
        for i in 0..4 {
            c = c.replace(&format!("<reference name=\"Out{i}\" />"), "<reference name=\"Stations\" />");
        }
        c.replace("Act_Log", "Note").replace("Act_Clear", "Note")
    };
    let mut main_vars = vars.clone();
    for i in 0..6 {
        main_vars.push_str(&var(&format!("In{i}"), "BOOL", "Operator panel"));
    }
    main_vars.push_str(&var("Level", "INT", "Tank level"));
    for i in 0..4 {
        main_vars.push_str(&var(&format!("Out{i}"), "BOOL", "Lamp on the operator panel"));
    }
    main_vars.push_str(&var("Count", "INT", "Cycles"));
    main_vars.push_str(&var("Run", "BOOL", "Machine running"));
    main_vars.push_str(&var("Notes", "INT", "Steps entered"));
    let main = format!(
        r#"
      <data name="http://www.3s-software.com/plcopenxml/pou" handleUnknown="implementation">
        <pou name="MAIN" pouType="program">
          <interface>
            <localVars>{main_vars}
            </localVars>
          </interface>
          <actions>{}{}
          </actions>
          <body>
            <SFC>{main_chart}
            </SFC>
          </body>
        </pou>
      </data>"#,
        st_action("Stations", &calls),
        st_action("Note", "Notes := Notes + 1;")
    );
    format!(
        r#"<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0200">
  <fileHeader companyName="" productName="CODESYS" productVersion="CODESYS V3.5 SP19 Patch 2" creationDateTime="2025-10-01T08:00:00.0000000" />
  <contentHeader name="Line.project" modificationDateTime="2025-10-01T08:00:00.0000000">
    <coordinateInfo><fbd><scaling x="1" y="1" /></fbd><ld><scaling x="1" y="1" /></ld><sfc><scaling x="1" y="1" /></sfc></coordinateInfo>
  </contentHeader>
  <types><dataTypes /><pous /></types>
  <instances>
    <configurations>
      <configuration name="Device">
        <resource name="Application">
          <task name="MainTask" interval="PT0.01S" priority="1"><pouInstance name="MAIN" typeName="" /></task>
          <addData>{pous}{main}
          </addData>
        </resource>
      </configuration>
    </configurations>
  </instances>
</project>
"#
    )
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let (blocks, steps, rounds) = if full { (59, 8, 5) } else { (3, 4, 1) };
    let dir = std::env::temp_dir().join(format!("sfc-bench-codesys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let xml = project(blocks, steps);
    let path = dir.join("line.xml");
    std::fs::write(&path, &xml).expect("project");
    let p = path.to_string_lossy().to_string();
    let mut times = Vec::new();
    for _ in 0..=rounds {
        let t = Instant::now();
        let out = Command::new(SFC).args(["check", &p]).output().expect("sfc runs");
        let dt = t.elapsed().as_secs_f64();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "sfc check failed:\n{err}");
        assert!(!err.contains("error["), "{err}");
        times.push(dt);
    }
    times.remove(0); // warm-up: the file cache
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    let total_steps = blocks * steps + steps.max(4) + 4;
    println!(
        "sfc check (analysis) of a CODESYS project export: {:.2} MB, {} SFC bodies ({} in actions), {} steps: {:.0} ms (median of {rounds}, {} build)",
        xml.len() as f64 / 1e6,
        blocks + 1,
        blocks,
        total_steps,
        median * 1e3,
        if cfg!(debug_assertions) { "debug" } else { "release" }
    );
    let _ = std::fs::remove_dir_all(&dir);
    if full {
        prove_machine();
    }
}

/// `sfc prove` on the machine project of issue 32 (the bottling line, a CODESYS export of eleven
/// function blocks whose SFC actions call each other's actions) with its property file, under
/// the `codesys` profile its vendor chooses: each property's verdict and time as `sfc prove`
/// prints it, the whole run's wall time and the child's peak resident memory. Targets: every
/// property decided within 10 s, peak memory under 1 GB.
fn prove_machine() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/real/codesys");
    let witnesses = std::env::temp_dir().join(format!("sfc-bench-prove-{}", std::process::id()));
    let t = Instant::now();
    let out = Command::new(SFC)
        .args(["prove", "bottling_line_eleven_blocks.xml", "--properties", "bottling_line.props.toml", "--witness-dir"])
        .arg(&witnesses)
        .current_dir(&dir)
        .output()
        .expect("sfc runs");
    let wall = t.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&out.stdout);
    println!("sfc prove of the bottling line (CODESYS export, profile codesys):");
    let mut verdict = String::new();
    for line in text.lines() {
        if ["HOLDS", "VIOLATED", "UNKNOWN"].iter().any(|v| line.starts_with(v)) {
            verdict = line.to_string();
        } else if let Some(m) = line.trim().strip_prefix("method: ") {
            let took = m.rsplit(", ").next().unwrap_or("");
            println!("  {verdict}  ({took})");
        } else if line.contains(" held, ") {
            println!("  {line}");
        }
    }
    println!("  wall time {wall:.2} s, peak memory {:.0} MiB", peak_child_kib() as f64 / 1024.0);
    let _ = std::fs::remove_dir_all(&witnesses);
}

/// The peak resident memory of the largest child waited for, KiB (`getrusage`).
fn peak_child_kib() -> i64 {
    #[cfg(unix)]
    {
        // SAFETY: `getrusage` writes the struct it is given; zeroed is a valid value for it.
        let mut u: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: RUSAGE_CHILDREN with a valid pointer.
        if unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut u) } == 0 {
            return u.ru_maxrss;
        }
    }
    0
}
