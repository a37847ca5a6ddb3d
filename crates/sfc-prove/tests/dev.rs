//! Development driver: `SFC_PROVE_DEV=chart.st cargo test -p sfc-prove --test dev -- --nocapture`
//! (`SFC_PROVE_PROFILE=codesys` for that profile).

#[test]
fn dev() {
    let Ok(chart) = std::env::var("SFC_PROVE_DEV") else { return };
    let text = std::fs::read_to_string(&chart).unwrap();
    let props_path = chart.replace(".st", ".props.toml");
    let props = std::fs::read_to_string(&props_path).unwrap();
    let file = sfc_prove::props::parse(&props_path, &props).unwrap();
    let profile = std::env::var("SFC_PROVE_PROFILE").ok().and_then(|p| sfc_sim::Profile::from_name(&p));
    let opts = sfc_prove::Options {
        seconds: 20.0,
        debug: std::env::var("SFC_PROVE_DEBUG").is_ok(),
        profile,
        ..Default::default()
    };
    match sfc_prove::prove(&chart, &text, &file, &opts) {
        Ok(r) => {
            println!("{}", r.human(""));
            for d in &r.debug {
                println!("  {d}");
            }
            for p in &r.properties {
                if let Some(w) = &p.witness {
                    println!("--- {}\n{}", w.file, w.text);
                    for d in &w.replay_detail {
                        println!("  replay: {d}");
                    }
                }
            }
        }
        Err(e) => println!("error: {e:?}"),
    }
}
