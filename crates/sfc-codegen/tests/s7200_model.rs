//! The S7-200 interpreter of `tests/s7200/` on hand-written programs: each test states a rule
//! of the System Manual (or of seed 002) and checks that the model follows it, so the
//! differential tests of the generator run against the hardware, not against a copy of the
//! generator's assumptions.

mod s7200;

use s7200::{parse, Plc, ScrModel, ScrtReset};

const MS: i64 = 1000;

fn plc(text: &str) -> Plc {
    Plc::new(parse(text).unwrap_or_else(|e| panic!("{e}\n{text}")))
}

#[test]
fn logic_stack() {
    let mut p = plc("NETWORK 1\n\
         LD I0.0\nLD I0.1\nO I0.2\nALD\n= Q0.0\n\
         NETWORK 2\n\
         LD I0.0\nLPS\nA I0.1\n= Q0.1\nLRD\nAN I0.1\n= Q0.2\nLPP\nNOT\n= Q0.3\n\
         NETWORK 3\n\
         LDN I0.0\nA I0.1\nLD I0.0\nAN I0.1\nOLD\n= Q0.4\n\
         NETWORK 4\n\
         LD I0.0\nLD I0.1\nLDS 1\nALD\nALD\n= Q0.5\n");
    for (a, b, c) in [(false, false, false), (true, false, true), (true, true, false), (false, true, true)] {
        p.set("I0.0", a).unwrap();
        p.set("I0.1", b).unwrap();
        p.set("I0.2", c).unwrap();
        p.scan(0).unwrap();
        assert_eq!(p.get("Q0.0").unwrap(), a && (b || c));
        assert_eq!(p.get("Q0.1").unwrap(), a && b);
        assert_eq!(p.get("Q0.2").unwrap(), a && !b);
        assert_eq!(p.get("Q0.3").unwrap(), !a);
        assert_eq!(p.get("Q0.4").unwrap(), a != b);
        assert_eq!(p.get("Q0.5").unwrap(), a && b, "LDS 1 copies the second level");
    }
    // Nine levels: a tenth load loses the bottom, which ALD then cannot read.
    let mut deep = String::from("NETWORK 1\n");
    deep.push_str(&"LD I0.0\n".repeat(10));
    deep.push_str(&"ALD\n".repeat(9));
    assert!(plc(&deep).scan(0).is_err());
    // Each network starts with an undefined stack.
    assert!(plc("NETWORK 1\nA I0.0\n= Q0.0\n").scan(0).is_err());
    assert!(parse("LDI I0.0\n").is_err(), "immediate instructions are not modelled");
    assert!(plc("LD SM0.0\n= I0.0\n").scan(0).is_err(), "inputs are read-only");
    assert!(parse("LD I0.0 // Prüfung\n").is_err(), "Micro/WIN text is ANSI: the model takes ASCII only");
}

#[test]
fn set_reset_edges_first_scan() {
    let mut p = plc("NETWORK 1\nLD SM0.1\nS M0.0, 3\n\
         NETWORK 2\nLD I0.0\nR M0.1, 2\n\
         NETWORK 3\nLD I0.1\nEU\n= Q0.0\n\
         NETWORK 4\nLD I0.1\nED\n= Q0.1\n\
         NETWORK 5\nLD SM0.0\n= Q0.2\n");
    p.set("I0.1", true).unwrap();
    p.scan(0).unwrap();
    assert!(p.get("M0.0").unwrap() && p.get("M0.1").unwrap() && p.get("M0.2").unwrap());
    assert!(p.get("Q0.0").unwrap(), "EU: rising edge in the first scan");
    assert!(!p.get("Q0.1").unwrap());
    assert!(p.get("Q0.2").unwrap());
    p.set("I0.0", true).unwrap();
    p.scan(MS).unwrap();
    assert!(p.get("M0.0").unwrap() && !p.get("M0.1").unwrap() && !p.get("M0.2").unwrap());
    assert!(!p.get("Q0.0").unwrap(), "EU: one scan only");
    p.set("I0.1", false).unwrap();
    p.scan(2 * MS).unwrap();
    assert!(p.get("Q0.1").unwrap(), "ED: falling edge");
    p.scan(3 * MS).unwrap();
    assert!(!p.get("Q0.1").unwrap());
    assert!(!p.get("SM0.1").unwrap());
}

/// System Manual, "Updating timers with 100-ms resolution": each execution adds the 100 ms
/// intervals counted since the start of the previous scan. Executed once per scan the timer
/// follows the time base; executed twice it gains time; not executed it loses time.
#[test]
fn timers_100ms_count_per_execution() {
    let mut once = plc("NETWORK 1\nLD I0.0\nTON T37, +30\n");
    let mut twice = plc("NETWORK 1\nLD I0.0\nTON T37, +30\nNETWORK 2\nLD I0.0\nTON T37, +30\n");
    let mut skipped = plc("NETWORK 1\nLD I0.1\nJMP 1\nNETWORK 2\nLD I0.0\nTON T37, +30\nNETWORK 3\nLBL 1\n");
    for p in [&mut once, &mut twice, &mut skipped] {
        p.set("I0.0", true).unwrap();
    }
    for k in 0..10i64 {
        skipped.set("I0.1", k % 2 == 1).unwrap();
        for p in [&mut once, &mut twice, &mut skipped] {
            p.scan(k * 100 * MS).unwrap();
        }
    }
    assert_eq!(once.timer_value(37), 9, "9 intervals after the scan that enabled it");
    assert_eq!(twice.timer_value(37), 18, "executed twice per scan: twice as fast");
    assert!(twice.executions()[&('T', 37)] == 2);
    assert_eq!(skipped.timer_value(37), 4, "not executed in every other scan: it loses those intervals");
}

/// The enabling execution adds the intervals since the start of the previous scan (the
/// accumulation runs independently of the enabling, so an interval can be up to 100 ms short);
/// with scans of 30 ms the value counts the time base's ticks, not the scan's elapsed time.
#[test]
fn timer_100ms_with_short_scans_counts_time_base_ticks() {
    let mut p = plc("NETWORK 1\nLD I0.0\nTON T37, +2\n");
    let mut values = Vec::new();
    for k in 0..12i64 {
        p.set("I0.0", k >= 3).unwrap(); // enabled in the scan at 90 ms
        p.scan(k * 30 * MS).unwrap();
        values.push((p.timer_value(37), p.get("T37").unwrap()));
    }
    // scans at 90 120 150 180 210 240 270 300 330: ticks 0 1 1 1 2 2 2 3 3; the scan at 90 ms
    // adds the ticks since the scan at 60 ms (none).
    let v: Vec<i64> = values.iter().map(|x| x.0).collect();
    assert_eq!(v, vec![0, 0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3]);
    assert!(!values[6].1 && values[7].1, "the bit at 2 ticks: 120 ms after enabling, not 200");
}

/// Figure 10-4 of the System Manual: the self-resetting timer `LDN T; TON T; LD T; = Q0.0`.
/// With a 10 ms timer Q0.0 never turns on (the bit is set at the top of the scan and cleared
/// by the timer box before the contact reads it); with a 100 ms timer it is on for one scan
/// each time the value reaches the preset; with a 1 ms timer only when the asynchronous update
/// falls between the two contacts.
#[test]
fn manual_figure_self_resetting_timer() {
    let prog = |t: u16, pt: i64| format!("NETWORK 1\nLDN T{t}\nTON T{t}, +{pt}\nNETWORK 2\nLD T{t}\n= Q0.0\n");
    let run = |p: &mut Plc, scans: i64, period: i64| -> usize {
        let mut on = 0;
        for k in 0..scans {
            p.scan(k * period).unwrap();
            on += usize::from(p.get("Q0.0").unwrap());
        }
        on
    };
    let mut t10 = plc(&prog(33, 3));
    assert_eq!(run(&mut t10, 200, 7 * MS), 0, "10 ms: never on");
    let mut t100 = plc(&prog(37, 3));
    let on = run(&mut t100, 200, 40 * MS);
    assert!(on > 10, "100 ms: on for one scan each time the preset is reached ({on})");
    let mut t1 = plc(&prog(32, 30));
    t1.instruction_time = 150; // the program takes time: the 1 ms update can fall between
    let on1 = run(&mut t1, 400, 7_300);
    assert!(on1 > 0 && on1 < 400, "1 ms: sometimes ({on1})");
    // The corrected form (enable from NOT Q0.0) is on for one scan each time, at every resolution.
    let fixed = |t: u16, pt: i64| format!("NETWORK 1\nLDN Q0.0\nTON T{t}, +{pt}\nNETWORK 2\nLD T{t}\n= Q0.0\n");
    for (t, pt, period) in [(33u16, 3i64, 7 * MS), (37, 3, 40 * MS)] {
        let mut p = plc(&fixed(t, pt));
        let mut on = 0;
        let mut last = false;
        for k in 0..300 {
            p.scan(k * period).unwrap();
            let q = p.get("Q0.0").unwrap();
            assert!(!(q && last), "T{t}: Q0.0 on in two scans in a row");
            on += usize::from(q);
            last = q;
        }
        assert!(on > 10, "T{t}: {on}");
    }
}

#[test]
fn timers_10ms_update_at_scan_start_and_tonr_tof() {
    // 10 ms TON: the value changes at the start of a scan and stays for the whole scan.
    let mut p = plc("NETWORK 1\nLD I0.0\nTON T33, +5\nNETWORK 2\nLD T33\n= Q0.0\nNETWORK 3\nLD I0.0\nTON T34, +5\n");
    p.set("I0.0", true).unwrap();
    for k in 0..6i64 {
        p.scan(k * 20 * MS).unwrap();
    }
    assert_eq!(p.timer_value(33), 10);
    assert!(p.get("Q0.0").unwrap());
    // TONR (100 ms T5) holds while disabled, R clears it.
    let mut r = plc("NETWORK 1\nLD I0.1\nTONR T5, +4\nNETWORK 2\nLD I0.2\nR T5, 1\n");
    let mut seen = Vec::new();
    for k in 0..8i64 {
        r.set("I0.1", !(2..4).contains(&k)).unwrap();
        r.scan(k * 100 * MS).unwrap();
        seen.push((r.timer_value(5), r.get("T5").unwrap()));
    }
    assert_eq!(
        seen,
        vec![(0, false), (1, false), (1, false), (1, false), (2, false), (3, false), (4, true), (5, true)]
    );
    r.set("I0.2", true).unwrap();
    r.scan(800 * MS).unwrap();
    assert_eq!((r.timer_value(5), r.get("T5").unwrap()), (0, false), "R clears a TONR");
    assert!(plc("LD SM0.0\nTON T5, +3").scan(0).is_err(), "T5 is a TONR number");
    assert!(plc("LD SM0.0\nTON T40, +3\nTOF T40, +3").scan(0).is_err(), "one number is TON or TOF");
    // TOF (100 ms T38): on at once, off PT after the input fell.
    let mut f = plc("NETWORK 1\nLD I0.0\nTOF T38, +3\n");
    let mut bits = Vec::new();
    for k in 0..8i64 {
        f.set("I0.0", k < 2).unwrap();
        f.scan(k * 100 * MS).unwrap();
        bits.push(f.get("T38").unwrap());
    }
    assert_eq!(bits, vec![true, true, true, true, false, false, false, false]);
    assert_eq!(f.timer_value(38), 3, "stops at the preset");
}

/// Counters (System Manual, "Understanding the S7-200 counter instructions"; STL operands:
/// CTU reset = top of stack, count up = second level; CTD load = top, count down = second).
#[test]
fn counters() {
    let mut p = plc("NETWORK 1\nLD I0.0\nLD I0.1\nCTU C1, +3\n\
         NETWORK 2\nLD I0.2\nLD I0.3\nCTD C2, +2\n\
         NETWORK 3\nLD I0.4\nLD I0.5\nLD I0.6\nCTUD C3, +2\n");
    let pulses = |p: &mut Plc, input: &str, n: usize, t: &mut i64| {
        for _ in 0..n {
            for v in [true, false] {
                p.set(input, v).unwrap();
                p.scan(*t).unwrap();
                *t += 10 * MS;
            }
        }
    };
    let mut t = 0;
    pulses(&mut p, "I0.0", 2, &mut t);
    assert_eq!((p.value("C1").unwrap(), p.get("C1").unwrap()), (2, false));
    pulses(&mut p, "I0.0", 2, &mut t);
    assert_eq!((p.value("C1").unwrap(), p.get("C1").unwrap()), (4, true));
    p.set("I0.1", true).unwrap();
    p.scan(t).unwrap();
    assert_eq!((p.value("C1").unwrap(), p.get("C1").unwrap()), (0, false), "reset");
    // CTD: load, then down to 0 where the bit turns on and the count stops.
    p.set("I0.3", true).unwrap();
    p.scan(t).unwrap();
    assert_eq!((p.value("C2").unwrap(), p.get("C2").unwrap()), (2, false));
    p.set("I0.3", false).unwrap();
    pulses(&mut p, "I0.2", 3, &mut t);
    assert_eq!((p.value("C2").unwrap(), p.get("C2").unwrap()), (0, true));
    // CTUD: up and down, wraps at the limits.
    pulses(&mut p, "I0.4", 3, &mut t);
    pulses(&mut p, "I0.5", 1, &mut t);
    assert_eq!((p.value("C3").unwrap(), p.get("C3").unwrap()), (2, true));
    assert_eq!(p.executions()[&('C', 3)], 1);
    // R on counters.
    let mut r = plc("NETWORK 1\nLD I0.0\nLD SM0.0\nCTU C0, +1\nNETWORK 2\nLD I0.1\nR C0, 1\n");
    r.set("I0.1", true).unwrap();
    r.scan(0).unwrap();
    assert_eq!(r.value("C0").unwrap(), 0);
}

#[test]
fn words_and_compares() {
    let mut p = plc("NETWORK 1\nLD SM0.0\nMOVW +32767, VW0\nINCW VW0\nMOVW VW0, VW2\n\
         NETWORK 2\nLD SM0.0\nMOVD +100000, VD4\n+D VD4, VD4\nINCD VD4\nITD VW2, VD8\n\
         NETWORK 3\nLD SM0.0\nMOVW +7, VW12\n/I +0, VW12\nMOVW -7, VW14\n/I +2, VW14\n\
         NETWORK 4\nLDW= VW0, -32768\nAD> VD4, +200000\n= Q0.0\n\
         NETWORK 5\nLDN SM0.0\nMOVW +5, VW16\n");
    p.scan(0).unwrap();
    assert_eq!(p.value("VW0").unwrap(), -32768, "16-bit wrap-around");
    assert_eq!(p.value("VD4").unwrap(), 200001);
    assert_eq!(p.value("VD8").unwrap(), -32768, "ITD sign-extends");
    assert_eq!(p.value("VW12").unwrap(), 7, "division by zero leaves the output");
    assert!(p.get("SM1.3").unwrap());
    assert_eq!(p.value("VW14").unwrap(), -3, "division truncates toward zero");
    assert!(p.get("Q0.0").unwrap());
    assert_eq!(p.value("VW16").unwrap(), 0, "boxes need power flow");
    assert_eq!(p.value("VW0").unwrap(), (p.value("VD0").unwrap() >> 16), "big-endian: VW0 is VD0's high word");
}

/// The SCR segment example of seed 002 (figure 3-35): S0.1 and S0.2 alternate on I0.0/I0.1,
/// each segment drives its output through SM0.0. SCRT sets the next S bit at once, so a
/// segment later in the program runs in the same scan: two evolutions in one scan unless the
/// program prevents it. Checked under both readings of an inactive segment and of the reset.
#[test]
fn scr_segments() {
    let text = "NETWORK 1\nLD SM0.1\nS S0.1, 1\n\
         NETWORK 2\nLSCR S0.1\n\
         NETWORK 3\nLD SM0.0\n= Q0.1\n\
         NETWORK 4\nLD I0.0\nSCRT S0.2\n\
         NETWORK 5\nSCRE\n\
         NETWORK 6\nLSCR S0.2\n\
         NETWORK 7\nLD SM0.0\n= Q0.2\n\
         NETWORK 8\nLD I0.1\nSCRT S0.1\n\
         NETWORK 9\nSCRE\n";
    for model in [ScrModel::PowerOff, ScrModel::Skip] {
        for reset in [ScrtReset::Immediate, ScrtReset::AtScre] {
            let mut p = plc(text);
            p.scr_model = model;
            p.scrt_reset = reset;
            p.scan(0).unwrap();
            assert!(p.get("S0.1").unwrap() && p.get("Q0.1").unwrap() && !p.get("S0.2").unwrap());
            p.set("I0.0", true).unwrap();
            p.set("I0.1", true).unwrap();
            p.scan(MS).unwrap();
            // S0.1 -> S0.2 and, in the same scan, S0.2 -> S0.1 again.
            assert!(p.get("S0.1").unwrap() && !p.get("S0.2").unwrap(), "{model:?} {reset:?}");
            assert!(p.get("Q0.2").unwrap(), "the segment of S0.2 ran in the scan S0.2 was set");
            p.set("I0.1", false).unwrap();
            p.scan(2 * MS).unwrap();
            assert!(!p.get("S0.1").unwrap() && p.get("S0.2").unwrap());
            p.scan(3 * MS).unwrap();
            if model == ScrModel::PowerOff {
                assert!(!p.get("Q0.1").unwrap(), "a coil in an inactive segment is off");
            }
        }
    }
    assert!(plc("NETWORK 1\nLD SM0.0\nSCRT S0.1\n").scan(0).is_err(), "SCRT outside a segment");
    assert!(plc("NETWORK 1\nLSCR S0.1\nLD SM0.0\nSCRT S0.1\nSCRE\n").scan(0).is_err(), "SCRT to itself");
    assert!(plc("NETWORK 1\nLSCR S0.1\nNETWORK 2\nLBL 1\nNETWORK 3\nSCRE\n").scan(0).is_err(), "LBL in SCR");
    assert!(plc("NETWORK 1\nLSCR S0.1\n").scan(0).is_err(), "no SCRE");
}

#[test]
fn jumps() {
    let mut p = plc("NETWORK 1\nLD I0.0\nJMP 4\nNETWORK 2\nLD SM0.0\n= Q0.0\nNETWORK 3\nLBL 4\nLD SM0.0\n= Q0.1\n");
    p.scan(0).unwrap();
    assert!(p.get("Q0.0").unwrap() && p.get("Q0.1").unwrap());
    p.set("I0.0", true).unwrap();
    p.set("Q0.0", false).unwrap();
    p.scan(MS).unwrap();
    assert!(!p.get("Q0.0").unwrap() && p.get("Q0.1").unwrap());
    assert!(plc("NETWORK 1\nLD SM0.0\nJMP 9\n").scan(0).is_err(), "JMP without LBL");
}
