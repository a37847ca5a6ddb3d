//! The verdicts as the user reads them: one block per property (human) or one JSON object.

use crate::check::{fmt_states, Finding, Verdict};
use crate::compile::{Compiled, Origin};
use crate::witness::{Replay, Witness};

/// The witness directory that says the witnesses are not written (`--no-witness`).
pub const NOT_WRITTEN: &str = "(not written)";
use serde_json::json;
use std::time::Duration;

/// A witness attached to a verdict.
#[derive(Debug, Clone)]
pub struct WitnessInfo {
    /// The scenario file name (written beside the chart by the CLI).
    pub file: String,
    pub text: String,
    /// Scans of the run.
    pub scans: usize,
    /// The simulator reproduced it.
    pub replayed: bool,
    /// Failures of the replay (the property's own, when confirmed).
    pub replay_detail: Vec<String>,
    /// A file to write (violations; not the path of a reached goal).
    pub write: bool,
    /// The inputs to set before each scan (only those that change), as JSON values: what the
    /// editor's monitor replays.
    pub inputs: Vec<Vec<(String, serde_json::Value)>>,
}

/// The verdict of one property.
#[derive(Debug, Clone)]
pub struct PropertyReport {
    pub name: String,
    /// `property`, `range` or `runtime error`.
    pub kind: &'static str,
    /// Line of the `[[property]]` in the property file (0 for ranges and faults).
    pub line: u32,
    pub verdict: Verdict,
    pub method: &'static str,
    pub states: Option<f64>,
    /// Size of the inductive invariant (clauses, or diagram nodes of a reachable set) and
    /// whether its independent check passed.
    pub invariant: Option<(usize, bool)>,
    /// How many of the inductive invariant's constraints are at-most-one constraints.
    pub at_most_one: usize,
    pub message: String,
    pub depth: Option<usize>,
    pub witness: Option<WitnessInfo>,
    pub time: Duration,
}

impl PropertyReport {
    pub fn new(c: &Compiled, f: &Finding, time: Duration) -> PropertyReport {
        PropertyReport {
            name: c.name.clone(),
            kind: crate::origin_kind(&c.origin),
            line: 0,
            verdict: f.verdict,
            method: f.method,
            states: f.states,
            invariant: f.invariant,
            at_most_one: f.at_most_one,
            message: f.message.clone(),
            depth: f.depth,
            witness: None,
            time,
        }
    }

    /// Attaches a witness and its replay; a violation the simulator does not reproduce is
    /// not reported as one.
    pub fn attach(&mut self, w: Witness, file: String, text: String, replay: Replay, write: bool) {
        let scans = w.last + 1;
        if !replay.confirmed {
            let was = self.verdict;
            self.verdict = Verdict::Unknown;
            self.message = format!(
                "the engine found a {} in {} scans that the simulator does not reproduce ({}); please report this",
                if was == Verdict::Violated { "violation" } else { "path" },
                scans,
                replay.detail.first().cloned().unwrap_or_else(|| "the scenario passed".into())
            );
        } else if self.verdict == Verdict::Violated && self.message.is_empty() {
            self.message = format!("violated after scan {} (shortest witness: {} scans)", w.last, scans);
        }
        let inputs = w
            .sets
            .iter()
            .map(|scan| scan.iter().map(|(n, v)| (n.clone(), crate::witness::json_value(v))).collect())
            .collect();
        self.witness = Some(WitnessInfo {
            file,
            text,
            scans,
            replayed: replay.confirmed,
            replay_detail: replay.detail,
            write,
            inputs,
        });
    }
}

/// All verdicts of one `sfc prove` run.
#[derive(Debug, Clone)]
pub struct Report {
    pub chart: String,
    pub pou: String,
    pub period: i64,
    /// The profile proved under (`iec` or `codesys`).
    pub profile: sfc_sim::Profile,
    pub properties_file: String,
    pub state_bits: usize,
    /// The free inputs of every scan.
    pub inputs: Vec<String>,
    /// What the model does not hold exactly (over-approximations).
    pub notes: Vec<String>,
    pub properties: Vec<PropertyReport>,
    pub time: Duration,
    /// With `Options::debug`: the model's registers and figures.
    pub debug: Vec<String>,
}

impl Report {
    pub fn count(&self, v: Verdict) -> usize {
        self.properties.iter().filter(|p| p.verdict == v).count()
    }

    /// 0 when every property holds, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        u8::from(self.properties.iter().any(|p| p.verdict != Verdict::Holds))
    }

    /// The human report.
    pub fn human(&self, witness_dir: &str) -> String {
        let mut out = format!(
            "proving {} (POU {}) with {}: period {}, profile {}, {} state bits, inputs: {}\n",
            self.chart,
            self.pou,
            self.properties_file,
            sfc_sim::format_time(self.period),
            self.profile.name(),
            self.state_bits,
            if self.inputs.is_empty() { "none".to_string() } else { self.inputs.join(", ") }
        );
        for n in &self.notes {
            out.push_str(&format!("note: {n}\n"));
        }
        for p in &self.properties {
            let tag = match p.verdict {
                Verdict::Holds => "HOLDS    ",
                Verdict::Violated => "VIOLATED ",
                Verdict::Unknown => "UNKNOWN  ",
            };
            out.push_str(&format!("{tag}{}\n", p.name));
            let mut how = format!("method: {}", p.method);
            if let Some(s) = p.states {
                how.push_str(&format!(", {} reachable states", fmt_states(s)));
            }
            if let Some((n, ok)) = p.invariant {
                if p.method.starts_with("BDD") {
                    how.push_str(&format!(", reachable set of {n} diagram nodes"));
                } else if n > 0 {
                    let clauses = n - p.at_most_one.min(n);
                    how.push_str(&format!(
                        ", inductive invariant of {clauses} clause{}",
                        if clauses == 1 { "" } else { "s" }
                    ));
                    if p.at_most_one > 0 {
                        how.push_str(&format!(
                            " and {} at-most-one constraint{}",
                            p.at_most_one,
                            if p.at_most_one == 1 { "" } else { "s" }
                        ));
                    }
                }
                if p.verdict == Verdict::Holds {
                    how.push_str(if ok { ", invariant re-checked" } else { ", invariant check FAILED" });
                }
            }
            how.push_str(&format!(", {:.0?}", p.time));
            out.push_str(&format!("    {how}\n"));
            if !p.message.is_empty() {
                out.push_str(&format!("    {}\n", p.message));
            }
            if let Some(w) = &p.witness {
                if w.write {
                    let path = if witness_dir.is_empty() {
                        w.file.clone()
                    } else if witness_dir == NOT_WRITTEN {
                        format!("{} (not written)", w.file)
                    } else {
                        format!("{witness_dir}/{}", w.file)
                    };
                    out.push_str(&format!(
                        "    witness: {path} ({} scans, {} in the simulator)\n",
                        w.scans,
                        if w.replayed { "replayed" } else { "NOT reproduced" }
                    ));
                    if p.verdict == Verdict::Violated {
                        for d in w.replay_detail.iter().take(2) {
                            out.push_str(&format!("    {}\n", d.lines().next().unwrap_or("")));
                        }
                    }
                } else if w.replayed {
                    out.push_str(&format!("    reached in {} scans (replayed in the simulator)\n", w.scans));
                }
            }
        }
        out.push_str(&format!(
            "{} held, {} violated, {} unknown ({:.2?})\n",
            self.count(Verdict::Holds),
            self.count(Verdict::Violated),
            self.count(Verdict::Unknown),
            self.time
        ));
        out
    }

    /// The JSON report.
    pub fn json(&self, witness_dir: &str) -> serde_json::Value {
        let props: Vec<serde_json::Value> = self
            .properties
            .iter()
            .map(|p| {
                let witness = p.witness.as_ref().filter(|w| w.write).map(|w| {
                    json!({
                        "file": if witness_dir.is_empty() || witness_dir == NOT_WRITTEN { w.file.clone() } else { format!("{witness_dir}/{}", w.file) },
                        "written": witness_dir != NOT_WRITTEN,
                        "scans": w.scans,
                        "replayed": w.replayed,
                    })
                });
                json!({
                    "name": p.name,
                    "kind": p.kind,
                    "line": if p.line > 0 { json!(p.line) } else { json!(null) },
                    "verdict": p.verdict.name(),
                    "method": p.method,
                    "states": p.states,
                    "invariant": p.invariant.map(|(n, _)| n),
                    "invariant_checked": p.invariant.map(|(_, ok)| ok),
                    "message": p.message,
                    "depth": p.depth,
                    "witness": witness,
                    "reached_in": p.witness.as_ref().filter(|w| !w.write).map(|w| w.scans),
                    "seconds": p.time.as_secs_f64(),
                })
            })
            .collect();
        json!({
            "chart": self.chart,
            "pou": self.pou,
            "properties_file": self.properties_file,
            "period": sfc_sim::format_time(self.period),
            "profile": self.profile.name(),
            "state_bits": self.state_bits,
            "inputs": self.inputs,
            "notes": self.notes,
            "properties": props,
            "summary": {
                "holds": self.count(Verdict::Holds),
                "violated": self.count(Verdict::Violated),
                "unknown": self.count(Verdict::Unknown),
            },
            "seconds": self.time.as_secs_f64(),
        })
    }
}

/// For reports on user properties: their line.
pub fn line_of(c: &Compiled, file: &crate::props::PropertyFile) -> u32 {
    match c.origin {
        Origin::User(k) => file.properties.get(k).map_or(0, |p| p.line),
        _ => 0,
    }
}
