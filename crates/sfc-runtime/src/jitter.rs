//! Scan timing statistics in constant memory: a histogram of 1 µs buckets up to 100 ms (later
//! values share the last bucket; the maximum is kept exactly).

const BUCKETS: usize = 100_000;

/// A distribution of durations in µs.
#[derive(Debug, Clone)]
pub struct Histogram {
    counts: Vec<u32>,
    n: u64,
    max: u64,
    sum: u64,
}

impl Default for Histogram {
    fn default() -> Self {
        Histogram { counts: vec![0; BUCKETS], n: 0, max: 0, sum: 0 }
    }
}

impl Histogram {
    pub fn add(&mut self, us: u64) {
        let b = (us as usize).min(BUCKETS - 1);
        if let Some(c) = self.counts.get_mut(b) {
            *c = c.saturating_add(1);
        }
        self.n += 1;
        self.max = self.max.max(us);
        self.sum = self.sum.saturating_add(us);
    }
    pub fn count(&self) -> u64 {
        self.n
    }
    pub fn max(&self) -> u64 {
        self.max
    }
    pub fn mean(&self) -> u64 {
        self.sum.checked_div(self.n).unwrap_or(0)
    }
    /// The smallest value with at least `q` (0..=1) of the samples at or below it.
    pub fn quantile(&self, q: f64) -> u64 {
        if self.n == 0 {
            return 0;
        }
        let want = ((q * self.n as f64).ceil() as u64).clamp(1, self.n);
        let mut seen = 0u64;
        for (b, &c) in self.counts.iter().enumerate() {
            seen += u64::from(c);
            if seen >= want {
                return if b == BUCKETS - 1 { self.max } else { b as u64 };
            }
        }
        self.max
    }
    /// `{"p50":…,"p99":…,"max":…,"mean":…}` in µs.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({"p50": self.quantile(0.5), "p99": self.quantile(0.99), "max": self.max, "mean": self.mean()})
    }
}

/// What a run measured.
#[derive(Debug, Clone, Default)]
pub struct ScanStats {
    /// Scans run.
    pub scans: u64,
    /// Lateness of each scan's start against its deadline on the period grid, µs.
    pub jitter: Histogram,
    /// Time each scan took (inputs, chart, outputs, monitor state), µs.
    pub duration: Histogram,
    /// Scans that ended after the next deadline.
    pub overruns: u64,
    /// Grid periods skipped because of overruns (virtual time skipped them too).
    pub skipped: u64,
}

impl ScanStats {
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "scans": self.scans,
            "jitterUs": self.jitter.to_json(),
            "scanUs": self.duration.to_json(),
            "overruns": self.overruns,
            "skipped": self.skipped,
        })
    }
    /// One line for a terminal: `scans 1000, jitter p50 12 µs p99 80 µs max 300 µs, …`.
    pub fn summary(&self) -> String {
        format!(
            "{} scans; start jitter p50 {} µs, p99 {} µs, max {} µs; scan time p50 {} µs, p99 {} µs, max {} µs; {} overruns, {} periods skipped",
            self.scans,
            self.jitter.quantile(0.5),
            self.jitter.quantile(0.99),
            self.jitter.max(),
            self.duration.quantile(0.5),
            self.duration.quantile(0.99),
            self.duration.max(),
            self.overruns,
            self.skipped
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_of_a_known_distribution() {
        let mut h = Histogram::default();
        for us in 1..=100 {
            h.add(us);
        }
        h.add(250_000);
        assert_eq!(h.quantile(0.5), 51);
        assert_eq!(h.quantile(0.99), 100);
        assert_eq!(h.quantile(1.0), 250_000);
        assert_eq!(h.max(), 250_000);
        assert_eq!(Histogram::default().quantile(0.5), 0);
    }
}
