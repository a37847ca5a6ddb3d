//! Freeing large values off the paths that answer the client. The syntax tree and index of a
//! 10,000-step document take tens of milliseconds to free; the reader of the connection (which
//! replaces analyses) and the check worker (which is done with its tree once the diagnostics
//! are made) hand them to a thread of their own instead of waiting.

use crossbeam_channel::Sender;
use std::sync::OnceLock;

type Garbage = Box<dyn Send>;

static FREEING: OnceLock<Option<Sender<Garbage>>> = OnceLock::new();

/// Frees `value` on the freeing thread (started on first use); in place when there is none.
pub fn later<T: Send + 'static>(value: T) {
    let tx = FREEING.get_or_init(|| {
        let (tx, rx) = crossbeam_channel::unbounded::<Garbage>();
        std::thread::Builder::new()
            .name("sfc-lsp-free".into())
            // Dropping a tree recurses along it, as parsing does.
            .stack_size(64 << 20)
            .spawn(move || rx.iter().for_each(drop))
            .ok()
            .map(|_| tx)
    });
    match tx {
        Some(tx) => {
            if let Err(back) = tx.send(Box::new(value)) {
                drop(back.into_inner());
            }
        }
        None => drop(value),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    struct Flag(Arc<AtomicBool>);
    impl Drop for Flag {
        fn drop(&mut self) {
            self.0.store(true, Ordering::SeqCst);
        }
    }

    #[test]
    fn a_value_handed_over_is_freed() {
        let freed = Arc::new(AtomicBool::new(false));
        later(Flag(freed.clone()));
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while !freed.load(Ordering::SeqCst) && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        assert!(freed.load(Ordering::SeqCst));
    }
}
