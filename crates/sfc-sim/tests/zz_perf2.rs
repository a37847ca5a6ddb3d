#[test]
fn perf_scan() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/blinker/blinker.st")).unwrap();
    let mut sim = sfc_sim::Simulation::from_source("b.st", &text, None, Default::default()).unwrap_or_else(|_| panic!());
    let _ = sim.set("Start", sfc_sim::Value::Bool(true));
    let n = 2_000_000;
    let t = std::time::Instant::now();
    for _ in 0..n { let _ = sim.advance(); }
    println!("scan: {:.1} ns", t.elapsed().as_nanos() as f64 / n as f64);
}
