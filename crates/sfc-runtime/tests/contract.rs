//! The messages a running chart sends read back into the types of `sfc_runtime::contract`
//! (which refuse unknown fields), from which the editor's TypeScript types are generated.

mod common;

use common::{carwash, Client};
use sfc_runtime::contract::{Delta, Hello, Snapshot};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn messages_fit_the_contract_types() {
    let rt = carwash(10_000, false);
    let mut c = Client::connect(rt.monitor_addr().unwrap(), None).await;
    let hello = c.until_type("hello").await;
    let h: Hello = serde_json::from_value(hello.clone()).unwrap_or_else(|e| panic!("hello: {e}\n{hello:#}"));
    assert_eq!(h.pou, "CarWash");
    let snap = c.until_type("snapshot").await;
    let _: Snapshot = serde_json::from_value(snap.clone()).unwrap_or_else(|e| panic!("snapshot: {e}\n{snap:#}"));
    for _ in 0..3 {
        let d = c.until_type("delta").await;
        let _: Delta = serde_json::from_value(d.clone()).unwrap_or_else(|e| panic!("delta: {e}\n{d:#}"));
    }
    drop(c);
    rt.stop();
    let _ = rt.wait();
}
