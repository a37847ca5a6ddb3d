//! The watchdog: a supervisor thread that trips at the deadline of a scan that is still running.
//!
//! The scan thread only stamps each scan's start and end (two relaxed atomic stores). The
//! supervisor sleeps until the running scan's deadline (start + watchdog); if that scan is still
//! running then, it trips: it sets the simulation's interrupt flag, which the scan's budget
//! looks at every few thousand loop iterations or calls (so the scan returns within
//! microseconds with a located fault), puts the outputs of the process image to their safe
//! values and the board into FAULT itself, so Modbus and the monitor tell the fault even if the
//! scan never returned. The scan thread then completes the report (which step, action and line
//! were running) when the scan returns.

// Indices here come from tables this crate builds at start (the Modbus map, the variables) or
// are checked against the frame length just before (Modbus PDUs); the runtime work of issue 14
// landed after the workspace lints, and its conversion to `get` is still to do (ARCHITECTURE.md).
#![allow(clippy::indexing_slicing)]

use crate::board::{Hub, RunState};
use crate::io::{Image, IoPoint};
use crate::safe::SafeState;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What the scan thread tells the supervisor.
#[derive(Debug)]
pub struct ScanClock {
    /// The instant all others are counted from.
    pub epoch: Instant,
    /// Start of the running scan in µs since `epoch`, plus one; 0 between scans.
    started: AtomicU64,
    /// Scans begun.
    seq: AtomicU64,
    /// The number of the scan running (or last run).
    scan: AtomicU64,
    /// The supervisor tripped on the scan now running (or the last one).
    pub tripped: AtomicBool,
}

impl ScanClock {
    pub fn new() -> ScanClock {
        ScanClock {
            epoch: Instant::now(),
            started: AtomicU64::new(0),
            seq: AtomicU64::new(0),
            scan: AtomicU64::new(0),
            tripped: AtomicBool::new(false),
        }
    }

    /// Scan `scan` starts at `at`.
    #[inline]
    pub fn begin(&self, at: Instant, scan: u64) {
        self.seq.fetch_add(1, Ordering::Relaxed);
        self.scan.store(scan, Ordering::Relaxed);
        let us = at.saturating_duration_since(self.epoch).as_micros() as u64 + 1;
        self.started.store(us, Ordering::Release);
    }

    /// The scan ended.
    #[inline]
    pub fn end(&self) {
        self.started.store(0, Ordering::Release);
    }
}

impl Default for ScanClock {
    fn default() -> Self {
        ScanClock::new()
    }
}

/// Everything the supervisor needs.
pub struct Supervisor {
    pub clock: Arc<ScanClock>,
    pub watchdog: Duration,
    /// The simulation's interrupt flag.
    pub interrupt: Arc<AtomicBool>,
    pub hub: Arc<Hub>,
    pub image: Arc<Mutex<Image>>,
    pub points: Arc<Vec<IoPoint>>,
    pub safe: Arc<SafeState>,
}

impl Supervisor {
    /// Watches until the run stops.
    pub fn run(self) {
        let poll = (self.watchdog / 2).clamp(Duration::from_millis(1), Duration::from_millis(50));
        while !self.hub.stopping() {
            let started = self.clock.started.load(Ordering::Acquire);
            if started == 0 || self.clock.tripped.load(Ordering::Relaxed) {
                std::thread::sleep(poll);
                continue;
            }
            let seq = self.clock.seq.load(Ordering::Relaxed);
            let deadline = self.clock.epoch + Duration::from_micros(started - 1) + self.watchdog;
            let now = Instant::now();
            if now < deadline {
                std::thread::sleep((deadline - now).min(Duration::from_millis(50)));
                continue;
            }
            if self.clock.started.load(Ordering::Acquire) == started && self.clock.seq.load(Ordering::Relaxed) == seq {
                self.trip(now - (deadline - self.watchdog));
                // The scan thread tells the trip when the scan returns; a scan that does not
                // return within a moment is told from here.
                let told = Instant::now() + Duration::from_millis(250);
                while self.clock.started.load(Ordering::Acquire) == started && Instant::now() < told {
                    std::thread::sleep(Duration::from_millis(5));
                }
                if self.clock.started.load(Ordering::Acquire) == started {
                    self.hub.notice(format!(
                        "watchdog: scan {} ran past the watchdog of {} and has not stopped {} ms after its deadline; \
                         outputs at their safe values (FAULT)",
                        self.clock.scan.load(Ordering::Relaxed),
                        sfc_sim::format_time(self.watchdog.as_micros() as i64),
                        Instant::now().saturating_duration_since(deadline).as_millis()
                    ));
                }
            }
        }
    }

    fn trip(&self, running: Duration) {
        self.clock.tripped.store(true, Ordering::Relaxed);
        self.interrupt.store(true, Ordering::Relaxed);
        {
            let mut img = self.image.lock().unwrap_or_else(|e| e.into_inner());
            for (i, v) in &self.safe.points {
                img.put(&self.points[*i], v);
            }
            img.set_fault(crate::io::FAULT_WATCHDOG);
        }
        let mut b = self.hub.lock();
        if b.state != RunState::Fault {
            let fault = serde_json::json!({
                "kind": "watchdog",
                "message": format!("the scan ran past the watchdog of {} µs ({} µs so far)", self.watchdog.as_micros(), running.as_micros()),
            });
            b.set_state(RunState::Fault, Some(fault));
        }
    }
}
